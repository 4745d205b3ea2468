#pragma once
// A campaign's trials.csv as rows of fields without the column `answered_utc` (the
// wall-clock time of each answer, which differs between any two runs): what two runs of the
// same answers must agree on. Without the staging columns too (what was shown and heard:
// a run with the station shows a scene, one without shows none) for runs that differ in
// that alone.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "study/trials_table.h"

namespace doorbench::testing {

inline std::vector<std::vector<std::string>> trials_rows_without(
    const std::filesystem::path& trials_csv, const std::vector<std::string>& left_out) {
  const study::TrialsTable table = study::read_trials_table(trials_csv);
  std::vector<std::vector<std::string>> rows;
  for (const std::vector<std::string>& row : table.rows) {
    std::vector<std::string> kept;
    for (std::size_t c = 0; c < row.size(); ++c) {
      const std::string& name = table.column_names[c];
      if (std::find(left_out.begin(), left_out.end(), name) == left_out.end())
        kept.push_back(row[c]);
    }
    rows.push_back(kept);
  }
  return rows;
}

inline std::vector<std::vector<std::string>> trials_rows_without_time(
    const std::filesystem::path& trials_csv) {
  return trials_rows_without(trials_csv, {"answered_utc"});
}

inline std::vector<std::vector<std::string>> trials_rows_without_time_and_staging(
    const std::filesystem::path& trials_csv) {
  return trials_rows_without(
      trials_csv, {"answered_utc", "first_scene", "first_sounds", "second_scene", "second_sounds"});
}

// Column `name` of every row.
inline std::vector<std::string> trials_column(const std::filesystem::path& trials_csv,
                                              const std::string& name) {
  const study::TrialsTable table = study::read_trials_table(trials_csv);
  std::vector<std::string> values;
  for (std::size_t r = 0; r < table.rows.size(); ++r) values.push_back(table.value(r, name));
  return values;
}

}  // namespace doorbench::testing
