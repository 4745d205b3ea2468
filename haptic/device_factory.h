#pragma once
// Opens a haptic device by the URI the command line takes:
//   sim, sim:hapticmaster        the simulated HapticMaster with a virtual user's hand
//   sim:rotary                   the simulated 1-DOF rotary device with the same hand
//   hapticmaster://HOST[:PORT]   a HapticMaster over its TCP protocol (port 7654 by default)
// A simulated device runs on the real clock unless simulated_time is set (then the playback
// advances it tick by tick: tests, the demo, benchmarks).
#include <cstdint>
#include <memory>
#include <string>

#include "analysis/simulation/virtual_hand.h"
#include "haptic/device.h"
#include "haptic/door_mapping.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/simulated_hapticmaster.h"

namespace doorbench::haptic {

struct DeviceRequest {
  std::string uri = "sim";
  bool simulated_time = false;
  // The virtual user of a simulated device: one open-close cycle every hand.duration_s,
  // repeated while the playback lasts, with optional pushes off the arc.
  VirtualHandOptions hand;
  bool repeat_hand = true;
  PushOptions pushes;
  std::uint64_t seed = 1;
  double force_noise_rms = 0.1;      // N on the simulated force sensor
  HapticMasterOptions hapticmaster;  // timeouts and I/O rate of the real device's driver
};

struct OpenedDevice {
  std::unique_ptr<HapticDevice> device;
  SimulatedDevice* simulated = nullptr;  // the same device when it is simulated, else null
};

// Throws std::invalid_argument naming the URI when it is not one of the above.
OpenedDevice open_device(const DeviceRequest& request, const ArcGeometry& arc,
                         double handle_radius_m);

}  // namespace doorbench::haptic
