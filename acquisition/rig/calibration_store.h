#pragma once
// The calibration store: a directory with one JSON file per record, `<id>.json`, in the
// text of to_json(CalibrationRecord). Records are added, never changed: adding an id again with
// different contents is an error, so a session's copy and the store's always agree.
// docs/calibration.md describes the layout and where the store is.
//
// Where: an explicit directory (the command line's --calibrations, RigDefinition's
// calibration_store), else $DOORBENCH_CALIBRATIONS, else `calibrations/` in the rig
// file's folder.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/rig/calibration_record.h"

namespace doorbench {

inline constexpr const char* kCalibrationStoreVariable = "DOORBENCH_CALIBRATIONS";

// explicit_directory if not empty, else $DOORBENCH_CALIBRATIONS if set and not empty, else
// rig_base_dir / "calibrations".
std::filesystem::path calibration_store_directory(const std::filesystem::path& explicit_directory,
                                                  const std::filesystem::path& rig_base_dir);

// "<kind>-<serial>-v<version>", with characters other than letters, digits, '.', '_' and
// '-' in the serial replaced by '_' (ids name files and HDF5 groups).
std::string make_record_id(std::string_view sensor_kind, std::string_view sensor_serial,
                           int version);

class CalibrationStore {
 public:
  explicit CalibrationStore(std::filesystem::path directory);
  const std::filesystem::path& directory() const { return directory_; }

  // Every record in the store, by sensor kind, serial and version. A file that is not a
  // valid record is an error naming the file. A missing directory is an empty store.
  std::vector<CalibrationRecord> records() const;
  std::optional<CalibrationRecord> find(std::string_view id) const;
  // Throws std::runtime_error "no calibration record ID in DIR (N records: …)".
  CalibrationRecord get(std::string_view id) const;
  // The highest version for this sensor, if any.
  std::optional<CalibrationRecord> latest(std::string_view sensor_kind,
                                          std::string_view sensor_serial) const;
  int next_version(std::string_view sensor_kind, std::string_view sensor_serial) const;
  // Writes DIR/<id>.json (creating DIR). The same record again is accepted; a different
  // record under an existing id is refused. Returns the file's path.
  std::filesystem::path add(const CalibrationRecord& record) const;

 private:
  std::filesystem::path directory_;
};

// The record a rig channel's `calibration` value names: an id in the store, or "latest"
// (the store's highest version for the channel's sensor). Checks that it calibrates that
// sensor (kind, serial) into the channel's unit. Not for "nominal" (the sensor model's
// datasheet record, which the caller makes). Errors name the channel and the store.
CalibrationRecord resolve_channel_record(const CalibrationStore& store, std::string_view value,
                                         std::string_view channel, std::string_view sensor_kind,
                                         std::string_view sensor_serial, std::string_view unit);

}  // namespace doorbench
