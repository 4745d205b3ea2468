#pragma once
// What comedi devices this machine has: every /dev/comediN (or DIR/comediN) opened with a
// ComediApi and described: driver, board, subdevices with their type, channels, maxdata,
// ranges and command abilities. For `doorbench devices`.
#include <filesystem>
#include <string>
#include <vector>

#include "sensors/comedi_api.h"

namespace doorbench::sensors {

struct ComediSubdeviceInfo {
  unsigned index = 0;
  std::string type;  // "analog input", ...
  int flags = 0;
  int channels = 0;
  unsigned maxdata = 0;                             // of channel 0
  std::vector<std::pair<double, double>> ranges_V;  // channel 0's voltage ranges
  std::vector<std::string> other_ranges;            // ranges in other units, as text
  int buffer_bytes = 0;                             // command subdevices only
};

struct ComediDeviceInfo {
  std::string path;
  std::string error;  // not empty: the device could not be opened (and nothing else is set)
  std::string driver, board;
  std::vector<ComediSubdeviceInfo> subdevices;
};

// The device files DIR/comedi0, DIR/comedi1, … in numeric order (not the per-subdevice
// files comediN_subdM).
std::vector<std::filesystem::path> comedi_device_files(const std::filesystem::path& dir);

ComediDeviceInfo describe_comedi_device(const ComediApi& api, const std::filesystem::path& path);

// The listing `doorbench devices` prints; says clearly when there is no device.
std::string comedi_devices_report(const ComediApi& api, const std::filesystem::path& dir);

}  // namespace doorbench::sensors
