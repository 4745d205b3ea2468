#include "acquisition/rig/calibration_store.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <tuple>

namespace doorbench {

namespace fs = std::filesystem;

fs::path calibration_store_directory(const fs::path& explicit_directory,
                                     const fs::path& rig_base_dir) {
  if (!explicit_directory.empty()) return explicit_directory;
  if (const char* variable = std::getenv(kCalibrationStoreVariable); variable && *variable) {
    return variable;
  }
  return rig_base_dir / "calibrations";
}

std::string make_record_id(std::string_view sensor_kind, std::string_view sensor_serial,
                           int version) {
  std::string serial(sensor_serial.empty() ? std::string_view("unknown") : sensor_serial);
  for (char& c : serial) {
    const bool plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                       c == '.' || c == '_' || c == '-';
    if (!plain) c = '_';
  }
  return std::string(sensor_kind) + "-" + serial + "-v" + std::to_string(version);
}

CalibrationStore::CalibrationStore(fs::path directory) : directory_(std::move(directory)) {
  if (directory_.empty()) throw std::invalid_argument("calibration store: no directory given");
}

namespace {

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot read the calibration record");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

std::vector<CalibrationRecord> CalibrationStore::records() const {
  std::vector<CalibrationRecord> records;
  std::error_code error;
  if (!fs::is_directory(directory_, error)) return records;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory_)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".json") continue;
    CalibrationRecord record =
        calibration_record_from_json(read_text(entry.path()), entry.path().string());
    if (record.id != entry.path().stem().string()) {
      throw std::runtime_error(entry.path().string() + ": holds record " + record.id +
                               " (a store's file is named after its record's id)");
    }
    records.push_back(std::move(record));
  }
  std::sort(records.begin(), records.end(), [](const auto& a, const auto& b) {
    return std::tie(a.sensor_kind, a.sensor_serial, a.version, a.id) <
           std::tie(b.sensor_kind, b.sensor_serial, b.version, b.id);
  });
  return records;
}

std::optional<CalibrationRecord> CalibrationStore::find(std::string_view id) const {
  const fs::path file = directory_ / (std::string(id) + ".json");
  std::error_code error;
  if (id.empty() || !fs::is_regular_file(file, error)) return std::nullopt;
  return calibration_record_from_json(read_text(file), file.string());
}

CalibrationRecord CalibrationStore::get(std::string_view id) const {
  if (std::optional<CalibrationRecord> record = find(id)) return *record;
  const std::vector<CalibrationRecord> all = records();
  std::string known;
  for (std::size_t i = 0; i < all.size() && i < 8; ++i) known += (i ? ", " : "") + all[i].id;
  if (all.size() > 8) known += ", …";
  throw std::runtime_error("no calibration record " + std::string(id) + " in " +
                           directory_.string() + " (" + std::to_string(all.size()) + " records" +
                           (all.empty() ? "" : ": " + known) + ")");
}

std::optional<CalibrationRecord> CalibrationStore::latest(std::string_view sensor_kind,
                                                          std::string_view sensor_serial) const {
  std::optional<CalibrationRecord> best;
  for (CalibrationRecord& record : records()) {
    if (record.sensor_kind != sensor_kind || record.sensor_serial != sensor_serial) continue;
    if (!best || record.version >= best->version) best = std::move(record);
  }
  return best;
}

int CalibrationStore::next_version(std::string_view sensor_kind,
                                   std::string_view sensor_serial) const {
  const std::optional<CalibrationRecord> last = latest(sensor_kind, sensor_serial);
  return last ? last->version + 1 : 1;
}

fs::path CalibrationStore::add(const CalibrationRecord& record) const {
  if (std::string problem = record.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  if (record.id.find_first_of("/\\") != std::string::npos || record.id.front() == '.') {
    throw std::invalid_argument("calibration record id " + record.id + " cannot name a file");
  }
  const std::string json = to_json(record);
  const fs::path file = directory_ / (record.id + ".json");
  if (std::optional<CalibrationRecord> existing = find(record.id)) {
    if (to_json(*existing) == json) return file;
    throw std::runtime_error(file.string() + ": the store already holds a different record " +
                             record.id + " (records are never changed: make a new version)");
  }
  fs::create_directories(directory_);
  // Written beside and renamed, so that a reader never sees half a record.
  const fs::path partial = directory_ / ("." + record.id + ".json.partial");
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    out << json << "\n";
    if (!out) throw std::runtime_error(partial.string() + ": cannot write the calibration record");
  }
  fs::rename(partial, file);
  return file;
}

CalibrationRecord resolve_channel_record(const CalibrationStore& store, std::string_view value,
                                         std::string_view channel, std::string_view sensor_kind,
                                         std::string_view sensor_serial, std::string_view unit) {
  const std::string where = "channel " + std::string(channel) + ": ";
  CalibrationRecord record;
  if (value == "latest") {
    std::optional<CalibrationRecord> latest = store.latest(sensor_kind, sensor_serial);
    if (!latest) {
      throw std::runtime_error(where + "calibration \"latest\": " + store.directory().string() +
                               " holds no record for " + std::string(sensor_kind) + " " +
                               std::string(sensor_serial) + " (calibrate it first)");
    }
    record = std::move(*latest);
  } else {
    try {
      record = store.get(value);
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(where + error.what());
    }
  }
  if (record.sensor_kind != sensor_kind) {
    throw std::runtime_error(where + "calibration record " + record.id + " is for a " +
                             record.sensor_kind + ", not a " + std::string(sensor_kind));
  }
  if (!record.sensor_serial.empty() && record.sensor_serial != sensor_serial) {
    throw std::runtime_error(where + "calibration record " + record.id + " calibrates sensor " +
                             record.sensor_serial + ", not " + std::string(sensor_serial));
  }
  if (record.unit != unit) {
    throw std::runtime_error(where + "calibration record " + record.id + " gives " + record.unit +
                             ", but the channel's unit is " + std::string(unit));
  }
  return record;
}

}  // namespace doorbench
