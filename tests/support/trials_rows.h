#pragma once
// A campaign's trials.csv as rows of fields without the column `answered_utc` (the
// wall-clock time of each answer, which differs between any two runs): what two runs of the
// same answers must agree on.
#include <filesystem>
#include <string>
#include <vector>

#include "study/trials_table.h"

namespace doorbench::testing {

inline std::vector<std::vector<std::string>> trials_rows_without_time(
    const std::filesystem::path& trials_csv) {
  const study::TrialsTable table = study::read_trials_table(trials_csv);
  const std::size_t time = *table.find_column("answered_utc");
  std::vector<std::vector<std::string>> rows;
  for (std::vector<std::string> row : table.rows) {
    row.erase(row.begin() + static_cast<std::ptrdiff_t>(time));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace doorbench::testing
