#include "analysis/preprocessing/recording_file.h"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include "acquisition/session/import_units.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

bool is_hdf5_file(const std::string& path) {
  // Every HDF5 file starts with this signature (at offset 0 for files HDF5 itself made).
  static constexpr char kSignature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open for reading");
  char head[8] = {};
  in.read(head, sizeof head);
  return in.gcount() == 8 && std::equal(head, head + 8, kSignature);
}

PreparedData load_prepared_data(const std::string& path,
                                const PreprocessingOptions& preprocessing) {
  const bool session = is_hdf5_file(path);
  if (!session && (path.ends_with(".h5") || path.ends_with(".hdf5"))) {
    throw std::runtime_error(path +
                             ": not an HDF5 file (a session starts with the HDF5 "
                             "signature; a CSV recording is read only under another name)");
  }
  // Empty cells of a CSV are lost samples. A session is prepare_session's reading, kept
  // here to name a channel cut short (its cells are missing from its end).
  const Recording recording =
      session ? session_to_recording(SessionReader(path))
              : recording_from_table_with_columns(read_csv_file(path, EmptyCells::kMissing), path,
                                                  kCsvImportFirstHint);
  PreparedData data = prepare(recording, preprocessing);
  for (const auto& [key, value] : recording.metadata) {
    if (key != kCutShortKey) continue;
    data.warnings.push_back(std::string(kCutShortWarning) + value +
                            "; only the time where every channel has samples is fitted");
  }
  // A unit in doubt comes first: it is the likely cause of what preprocessing found (an angle
  // in degrees has physically impossible samples).
  std::vector<std::string> doubts = unit_doubts(recording);
  for (std::string& doubt : doubts) doubt.insert(0, kUnitDoubtWarning);
  data.warnings.insert(data.warnings.begin(), doubts.begin(), doubts.end());
  if (data.handle_radius_m > 0 && data.geometry_calibration_id.empty()) {
    data.handle_radius_origin = session ? "the session's handle_radius_m attribute"
                                        : "the CSV's metadata (# handle_radius_m)";
  }
  return data;
}

}  // namespace doorbench
