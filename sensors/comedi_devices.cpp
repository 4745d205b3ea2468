#include "sensors/comedi_devices.h"

#include <algorithm>
#include <cstdlib>
#include <regex>
#include <sstream>

namespace doorbench::sensors {

namespace fs = std::filesystem;

std::vector<fs::path> comedi_device_files(const fs::path& dir) {
  std::vector<std::pair<unsigned long, fs::path>> found;
  std::error_code error;
  static const std::regex name("comedi([0-9]+)");
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, error)) {
    std::smatch match;
    const std::string file = entry.path().filename().string();
    if (std::regex_match(file, match, name)) {
      found.emplace_back(std::strtoul(match[1].str().c_str(), nullptr, 10), entry.path());
    }
  }
  std::sort(found.begin(), found.end());
  std::vector<fs::path> paths;
  for (auto& [number, path] : found) paths.push_back(path);
  return paths;
}

ComediDeviceInfo describe_comedi_device(const ComediApi& api, const fs::path& path) {
  ComediDeviceInfo info;
  info.path = path.string();
  comedi_t* device = api.open(info.path.c_str());
  if (device == nullptr) {
    info.error = api.last_error();
    return info;
  }
  const char* driver = api.get_driver_name(device);
  const char* board = api.get_board_name(device);
  info.driver = driver ? driver : "?";
  info.board = board ? board : "?";
  const int subdevices = api.get_n_subdevices(device);
  for (int s = 0; s < subdevices; ++s) {
    ComediSubdeviceInfo sub;
    const auto index = static_cast<unsigned>(s);
    sub.index = index;
    sub.type = comedi_subdevice_type_name(api.get_subdevice_type(device, index));
    sub.flags = api.get_subdevice_flags(device, index);
    sub.channels = api.get_n_channels(device, index);
    if (sub.channels > 0) {
      sub.maxdata = api.get_maxdata(device, index, 0);
      const int ranges = api.get_n_ranges(device, index, 0);
      for (int r = 0; r < ranges; ++r) {
        const comedi_range* range = api.get_range(device, index, 0, static_cast<unsigned>(r));
        if (range == nullptr) continue;
        if (range->unit == UNIT_volt) {
          sub.ranges_V.emplace_back(range->min, range->max);
        } else {
          std::ostringstream text;
          text << "[" << range->min << ", " << range->max << "] "
               << (range->unit == UNIT_mA ? "mA" : "(no unit)");
          sub.other_ranges.push_back(text.str());
        }
      }
    }
    if (sub.flags > 0 && (sub.flags & (SDF_CMD_READ | SDF_CMD_WRITE))) {
      sub.buffer_bytes = api.get_buffer_size(device, index);
    }
    info.subdevices.push_back(sub);
  }
  api.close(device);
  return info;
}

std::string comedi_devices_report(const ComediApi& api, const fs::path& dir) {
  std::ostringstream out;
  const std::vector<fs::path> files = comedi_device_files(dir);
  if (files.empty()) {
    out << "no comedi devices: " << (dir / "comedi*").string()
        << " does not exist (comedi needs a supported card and its kernel driver; the study's "
           "USB cDAQ-9172 has no comedi driver)\n";
    return out.str();
  }
  for (const fs::path& file : files) {
    const ComediDeviceInfo info = describe_comedi_device(api, file);
    if (!info.error.empty()) {
      out << info.path << ": cannot open: " << info.error << "\n";
      continue;
    }
    out << info.path << ": driver " << info.driver << ", board " << info.board << ", "
        << info.subdevices.size() << " subdevices\n";
    for (const ComediSubdeviceInfo& sub : info.subdevices) {
      out << "  subdevice " << sub.index << ": " << sub.type;
      if (sub.channels <= 0) {
        out << "\n";
        continue;
      }
      out << ", " << sub.channels << " channels, maxdata " << sub.maxdata;
      std::string abilities;
      auto add = [&](int flag, const char* name) {
        if (sub.flags > 0 && (sub.flags & flag))
          abilities.append(abilities.empty() ? "" : " ").append(name);
      };
      add(SDF_CMD_READ, "commands(read)");
      add(SDF_CMD_WRITE, "commands(write)");
      add(SDF_SOFT_CALIBRATED, "soft-calibrated");
      add(SDF_LSAMPL, "32-bit-samples");
      std::string arefs;
      auto aref = [&](int flag, const char* name) {
        if (sub.flags > 0 && (sub.flags & flag))
          arefs.append(arefs.empty() ? "" : " ").append(name);
      };
      aref(SDF_GROUND, "ground");
      aref(SDF_COMMON, "common");
      aref(SDF_DIFF, "diff");
      aref(SDF_OTHER, "other");
      if (!arefs.empty()) out << ", aref " << arefs;
      if (!abilities.empty()) out << ", " << abilities;
      if (sub.buffer_bytes > 0) out << ", buffer " << sub.buffer_bytes << " bytes";
      out << "\n";
      if (!sub.ranges_V.empty()) {
        out << "    ranges (V):";
        for (std::size_t r = 0; r < sub.ranges_V.size(); ++r) {
          out << " " << r << ":[" << sub.ranges_V[r].first << ", " << sub.ranges_V[r].second << "]";
        }
        out << "\n";
      }
      for (const std::string& other : sub.other_ranges) out << "    range " << other << "\n";
    }
  }
  return out.str();
}

}  // namespace doorbench::sensors
