// Fuzzes the CSV exchange format (acquisition/session/csv_table.h, recording_csv.h) and the
// dialects import reads: any text gives a table and a recording, or a CsvError; nothing else
// may escape, crash or be undefined. A recording read back is written and read again: the
// writer must accept what the reader gave and give the same samples back.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string_view>

#include "acquisition/session/recording_csv.h"

namespace {

bool same(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // The exchange format, and the dialects doorbench import reads (--separator, --decimal-comma,
  // a --map time column of dates and times).
  for (const doorbench::CsvDialect dialect :
       {doorbench::CsvDialect{}, doorbench::CsvDialect{';', true, ""},
        doorbench::CsvDialect{'\t', false, ""}, doorbench::CsvDialect{',', false, "time_s"}}) {
    try {
      doorbench::parse_csv_table(text, "fuzz.csv", doorbench::EmptyCells::kMissing, dialect);
    } catch (const doorbench::CsvError&) {
    }
  }
  doorbench::Recording recording;
  try {
    recording = doorbench::parse_recording_csv(text, "fuzz.csv", doorbench::EmptyCells::kMissing);
  } catch (const doorbench::CsvError&) {
    return 0;
  }
  std::ostringstream written;
  doorbench::write_recording_csv(written, recording);
  const doorbench::Recording back =
      doorbench::parse_recording_csv(written.str(), "again.csv", doorbench::EmptyCells::kMissing);
  if (!same(back.time_s, recording.time_s) || !same(back.force_N, recording.force_N) ||
      back.extra_names != recording.extra_names || back.stroke != recording.stroke) {
    std::abort();  // the round trip changed the recording
  }
  return 0;
}
