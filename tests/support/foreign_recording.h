#pragma once
// A recording "from elsewhere" for the tests of any sample rate and geometry: a door model opened
// and closed by the virtual hand, sampled at jittered times around a low rate, the angle quantised
// as an encoder's, the force with an offset (a load cell not tared) and white noise, no rate and no
// stroke column, and the handle radius stated in the metadata. The samples are the simulator's at
// the jittered times themselves (no resampling).
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "acquisition/session/recording_csv.h"
#include "analysis/model/door_model.h"
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"

namespace doorbench::testing {

struct ForeignRecordingOptions {
  double rate_hz = 50.0;
  double jitter_s = 0.005;  // intervals uniform in 1/rate ± jitter_s
  double angle_quantum_rad = 0.001;
  double force_offset_N = 0.5;
  double force_noise_N = 0.2;
  std::vector<double> targets_rad = {1.3, 1.0, 1.4};  // one open-close cycle each
  double cycle_s = 8.0;
  std::uint32_t seed = 19;
};

// `model`'s handle radius is the one stated in the metadata and used by the hand.
// `true_omega_rad_s`, when given, receives the true rate at every sample.
inline Recording foreign_recording(const DoorModel& model, const ForeignRecordingOptions& options,
                                   std::vector<double>* true_omega_rad_s = nullptr) {
  std::mt19937 random(options.seed);
  std::uniform_real_distribution<double> jitter(-options.jitter_s, options.jitter_s);
  std::normal_distribution<double> noise(0.0, options.force_noise_N);
  const double radius_m = model.geometry().handle_radius_m;
  Recording recording;
  recording.source = "foreign recording";
  recording.handle_radius_m = radius_m;
  recording.angle_rad.emplace();
  // One clock for the whole recording, cut into the cycles.
  std::vector<double> clock;
  const double end_s = options.cycle_s * static_cast<double>(options.targets_rad.size());
  for (double t = 0.0; t < end_s; t += 1.0 / options.rate_hz + jitter(random)) clock.push_back(t);
  DoorState state;
  std::size_t next = 0;
  for (std::size_t cycle = 0; cycle < options.targets_rad.size(); ++cycle) {
    VirtualHandOptions hand_options;
    hand_options.target_angle_rad = options.targets_rad[cycle];
    hand_options.duration_s = options.cycle_s;
    const VirtualHand hand(hand_options, radius_m);
    const double offset_s = options.cycle_s * static_cast<double>(cycle);
    std::vector<double> times;
    while (next < clock.size() && clock[next] < offset_s + options.cycle_s) {
      times.push_back(clock[next++] - offset_s);
    }
    state.time_s = times.front();
    const Trajectory run = simulate(model, hand, state, times);
    for (std::size_t i = 0; i < run.size(); ++i) {
      recording.time_s.push_back(offset_s + run.time_s[i]);
      recording.force_N.push_back(run.force_N[i] + options.force_offset_N + noise(random));
      if (true_omega_rad_s) true_omega_rad_s->push_back(run.omega_rad_s[i]);
      recording.angle_rad->push_back(options.angle_quantum_rad *
                                     std::round(run.theta_rad[i] / options.angle_quantum_rad));
    }
    state.theta_rad = run.theta_rad.back();
    state.omega_rad_s = run.omega_rad_s.back();
  }
  return recording;
}

}  // namespace doorbench::testing
