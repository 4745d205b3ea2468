// Not a Google Benchmark: the render loop's timing for docs/PERFORMANCE.md.
//
//   doorbench_haptic_timing ticks N
//       N ticks of the sensory reference door on a device that costs nothing, in simulated
//       time; run it under callgrind with --toggle-collect to count a tick's instructions.
//   doorbench_haptic_timing realtime SECONDS [RATE_HZ]
//       the real-time runner on the simulated HapticMaster (real clock, the virtual user
//       opening and closing the door), every tick streamed into a session in /tmp; meanwhile
//       the control thread changes the parameters every 0.5 s and measures each change's time
//       from publish() to the tick that takes it. Prints the timing report and the latencies.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "bench/haptic_fixed_device.h"
#include "core/percentile.h"
#include "fixtures/temp_dir.h"
#include "haptic/device_factory.h"
#include "haptic/playback.h"

using namespace doorbench;

namespace {

int run_ticks(long count) {
  const DoorModel model = reference_model(ModelKind::kSensory);
  const haptic::DoorMapping mapping(haptic::Kinematics::kCartesian3, haptic::ArcGeometry{},
                                    model.geometry().handle_radius_m);
  bench::FixedPathDevice device(mapping);
  haptic::RenderLoopOptions options;
  options.safety.max_tick_interval_s = 1e9;
  haptic::RenderLoop loop(device, mapping,
                          std::make_unique<haptic::PlaybackParameters>(model, mapping, "bench"),
                          options);
  for (long tick = 0; tick < count; ++tick) {
    loop.tick(static_cast<double>(tick) * 1e-3);
    if (tick % 50000 == 49999) {
      while (loop.records().consumer_slot()) loop.records().release();
    }
  }
  std::printf("%ld ticks; last command %.6g N\n", count, device.last_command().norm());
  return 0;
}

int run_realtime(double seconds, double rate_hz) {
  const DoorModel model = reference_model(ModelKind::kSensory);
  haptic::DeviceRequest request;
  request.uri = "sim";
  request.hand.duration_s = 10.0;
  haptic::PlaybackOptions options;
  options.duration_s = seconds;
  options.loop.rate_hz = rate_hz;
  options.loop.safety.max_force = 100.0;
  options.loop.safety.max_force_rate = 20000.0;
  // A measurement of the timing: a late tick is counted (intervals over 5 ms), not tripped on.
  options.loop.safety.max_tick_interval_s = 1.0;
  haptic::OpenedDevice opened =
      haptic::open_device(request, options.arc, model.geometry().handle_radius_m);
  const testing::TempDir dir("haptic_timing");
  const std::filesystem::path path = dir / "timing.h5";
  SessionMetadata metadata;
  metadata.rig_name = "haptic timing benchmark";
  haptic::Playback playback(*opened.device, model, options, path, metadata,
                            haptic::PlaybackSetup{opened.device->name(), "reference door", ""});
  std::vector<double> latencies_us;
  int pending_id = 0;
  double pending_published_s = 0.0;
  int calls = 0;
  bool heavier = false;
  const haptic::PlaybackSummary summary = playback.run_real_time(
      [&](const haptic::RenderLoop::Status&) {
        haptic::ParameterMailbox& mailbox = playback.loop().mailbox();
        if (pending_id != 0 && mailbox.in_use() == pending_id) {
          latencies_us.push_back((mailbox.taken_time_s() - pending_published_s) * 1e6);
          pending_id = 0;
        }
        if (++calls % 10 == 0 && pending_id == 0) {
          heavier = !heavier;
          const DoorModel next =
              perceptual::set(model, perceptual::Control::kHeaviness, heavier ? 1.0 : 0.95);
          pending_id = mailbox.next_id();
          if (!playback.change_parameters(next, heavier ? "heavier" : "reference").empty()) {
            pending_id = 0;
          } else {
            pending_published_s = mailbox.last_published_time_s();
          }
        }
        return true;
      },
      0.05);
  std::printf("%s\n", summary.brief_report().c_str());
  std::printf(
      "parameter change -> first tick: %zu changes, p50 %.1f us, p99 %.1f us, max %.1f us\n",
      latencies_us.size(), percentile(latencies_us, 0.5), percentile(latencies_us, 0.99),
      latencies_us.empty() ? 0.0 : *std::max_element(latencies_us.begin(), latencies_us.end()));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "ticks" && argc > 2) return run_ticks(std::atol(argv[2]));
  if (mode == "realtime" && argc > 2) {
    return run_realtime(std::atof(argv[2]), argc > 3 ? std::atof(argv[3]) : 1000.0);
  }
  std::fprintf(stderr, "usage: %s ticks N | realtime SECONDS [RATE_HZ]\n", argv[0]);
  return 2;
}
