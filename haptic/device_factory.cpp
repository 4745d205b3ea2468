#include "haptic/device_factory.h"

#include <stdexcept>

#include "haptic/hapticmaster_device.h"
#include "haptic/rotary_device.h"

namespace doorbench::haptic {

OpenedDevice open_device(const DeviceRequest& request, const ArcGeometry& arc,
                         double handle_radius_m) {
  OpenedDevice opened;
  const std::string& uri = request.uri;
  SimulatedDeviceOptions device_options;
  device_options.clock = request.simulated_time ? SimClock::kManual : SimClock::kRealTime;
  device_options.seed = request.seed;
  device_options.force_noise_rms = request.force_noise_rms;
  if (uri == "sim" || uri == "sim:hapticmaster") {
    SimulatedHapticMasterOptions options;
    options.device = device_options;
    auto device = std::make_unique<SimulatedHapticMaster>(options);
    const DoorMapping mapping(Kinematics::kCartesian3, arc, handle_radius_m);
    SimulatedHandOptions hand;
    hand.hand = request.hand;
    hand.handle_radius_m = handle_radius_m;
    hand.repeat = request.repeat_hand;
    hand.pushes = request.pushes;
    device->set_hand(hand, mapping);
    opened.simulated = device.get();
    opened.device = std::move(device);
    return opened;
  }
  if (uri == "sim:rotary") {
    SimulatedRotaryOptions options;
    options.device = device_options;
    options.device.force_noise_rms = request.force_noise_rms * handle_radius_m;  // N*m
    auto device = std::make_unique<SimulatedRotaryDevice>(options);
    RotaryHandOptions hand;
    hand.hand = request.hand;
    hand.handle_radius_m = handle_radius_m;
    hand.repeat = request.repeat_hand;
    hand.pushes = request.pushes;
    device->set_hand(hand);
    opened.simulated = device.get();
    opened.device = std::move(device);
    return opened;
  }
  constexpr std::string_view kHapticMaster = "hapticmaster://";
  if (uri.rfind(kHapticMaster, 0) == 0) {
    const std::string address = uri.substr(kHapticMaster.size());
    if (address.empty()) {
      throw std::invalid_argument("--device '" + uri + "': no host (hapticmaster://HOST[:PORT])");
    }
    opened.device = std::make_unique<HapticMasterDevice>(address, request.hapticmaster);
    return opened;
  }
  throw std::invalid_argument("--device '" + uri +
                              "': not a device (use sim, sim:hapticmaster, sim:rotary or "
                              "hapticmaster://HOST[:PORT])");
}

}  // namespace doorbench::haptic
