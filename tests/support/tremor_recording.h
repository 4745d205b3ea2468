#pragma once
// Synthetic recordings made by a human-like hand with tremor, for the residual loop's
// tests and benchmark (docs/residual-loop.md, "Recordings with the tremor hand"): a
// different generator from synthetic_strokes' plain virtual hand, so that the loop is not
// only checked on the data it was tuned on.
//
// Each run is the virtual hand (analysis/simulation/virtual_hand.h) with
//   - its target angle and duration jittered per seed (±0.05 rad, ±10%),
//   - a physiological tremor: the hand's grip point shakes along the handle's arc by a sum
//     of three sinusoids of 8–12 Hz (random frequencies and phases per run) of
//     `tremor_amplitude_m` together, felt through the grip's stiffness (0.5 mm is 0.15 N
//     at the default 300 N/m), and a slow 1–2 Hz drift of the push of `drift_force_N`,
//   - a softer grip than the plain hand's (300 against 2000 N/m): the push builds up while
//     the door's friction holds it, as a relaxed arm's does,
//   - 0.3 s of the rest before each stroke kept in the stroke (the door held, shaken by the
//     tremor), as preprocessing keeps a margin of rest around the strokes it finds,
// both scaled by the grip (nothing once the hand lets go). As in synthetic_strokes, the
// run is simulated under the hand, its force sampled, and simulated again under the
// sampled force (so the data is exactly what a model driven by the recorded force does);
// then the bench's Gaussian noise is added to force, angle and rate.
//
// Contract: deterministic for a seed; runs * 2 strokes (opening id 2r+1, closing 2r+2);
// the PreparedData's noise levels are the bench's. Header-only, test and benchmark code.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"
#include "analysis/simulation/fit_synthetic.h"
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"
#include "core/units.h"

namespace doorbench::testing {

struct TremorRecordingOptions {
  int runs = 6;  // 12 strokes
  double sample_rate_hz = 1000.0;
  double tremor_amplitude_m = 0.5e-3;  // the grip point's shake, all three components
  double drift_force_N = 1.0;          // the slow variation of the push
  // The grip's impedance along the arc: softer than the plain virtual hand's 2000 N/m, as a
  // relaxed arm is, so that the push builds up while the door is held by its friction.
  double grip_stiffness_N_per_m = 300.0;
  double grip_damping_N_s_per_m = 60.0;
  // Rest kept before each stroke (the door held still, shaken by the tremor), as
  // preprocessing keeps a margin of rest around the strokes it finds.
  double rest_before_s = 0.3;
  double force_noise_N = 0.2;  // the bench's noise
  double angle_noise_rad = 0.01 * kRadPerDeg;
  double rate_noise_rad_s = 0.05 * kRadPerDeg;
  std::uint32_t seed = 1;
};

// The virtual hand plus tremor and drift (see the header comment).
class TremorHand final : public UserForce {
 public:
  TremorHand(const VirtualHandOptions& options, double handle_radius_m, double tremor_amplitude_m,
             double drift_force_N, std::mt19937& random)
      : hand_(options, handle_radius_m), stiffness_N_per_m_(options.stiffness_N_per_m) {
    std::uniform_real_distribution<double> tremor_hz(8.0, 12.0), drift_hz(1.0, 2.0),
        phase(0.0, 2.0 * kPi), weight(0.5, 1.0);
    double total = 0.0;
    for (Component& c : tremor_) {
      c = {tremor_hz(random), phase(random), weight(random)};
      total += c.amplitude;
    }
    for (Component& c : tremor_) c.amplitude *= tremor_amplitude_m / total;
    drift_ = {drift_hz(random), phase(random), drift_force_N};
  }

  double force_N(double time_s, double theta_rad, double omega_rad_s) const override {
    const double grip = hand_.reference(time_s).grip;
    if (grip <= 0.0) return 0.0;
    double shake_m = 0.0;
    for (const Component& c : tremor_) shake_m += c.value(time_s);
    return hand_.force_N(time_s, theta_rad, omega_rad_s) +
           grip * (stiffness_N_per_m_ * shake_m + drift_.value(time_s));
  }
  const VirtualHand& hand() const { return hand_; }

 private:
  static constexpr double kPi = 3.14159265358979323846;
  struct Component {
    double frequency_hz = 0.0, phase_rad = 0.0, amplitude = 0.0;
    double value(double t) const {
      return amplitude * std::sin(2.0 * kPi * frequency_hz * t + phase_rad);
    }
  };
  VirtualHand hand_;
  double stiffness_N_per_m_;
  Component tremor_[3];
  Component drift_;
};

inline PreparedData tremor_recording(const DoorModel& model,
                                     const TremorRecordingOptions& options) {
  PreparedData data;
  data.source = "tremor hand, seed " + std::to_string(options.seed);
  data.handle_radius_m = model.geometry().handle_radius_m;
  data.sample_rate_hz = options.sample_rate_hz;
  data.rate_noise_rad_s = options.rate_noise_rad_s;
  data.angle_noise_rad = options.angle_noise_rad;
  std::mt19937 random(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double r_h = model.geometry().handle_radius_m;
  for (int r = 0; r < options.runs; ++r) {
    VirtualHandOptions hand_options;
    const double fraction = options.runs > 1 ? r / static_cast<double>(options.runs - 1) : 0.5;
    hand_options.target_angle_rad = 0.5 + 0.9 * fraction + 0.05 * unit(random);
    hand_options.duration_s = (3.0 + 1.5 * fraction) * (1.0 + 0.1 * unit(random));
    hand_options.stiffness_N_per_m = options.grip_stiffness_N_per_m;
    hand_options.damping_N_s_per_m = options.grip_damping_N_s_per_m;
    const TremorHand hand(hand_options, r_h, options.tremor_amplitude_m, options.drift_force_N,
                          random);
    const SampledRun sampled =
        simulate_sampled_run(model, hand, hand_options.duration_s, options.sample_rate_hz);
    const std::vector<double>& times = sampled.times_s;
    const Trajectory& run = sampled.run;
    const SampleNoise noise{options.force_noise_N, options.angle_noise_rad,
                            options.rate_noise_rad_s};
    for (int marker : {1, 2}) {
      // The stroke with the rest before it (up to rest_before_s), where the door starts.
      const auto in_stroke = [&](std::size_t i) {
        const double lead_s = std::min(options.rest_before_s, times[i]);
        return hand.hand().stroke_at(times[i]) == marker ||
               hand.hand().stroke_at(times[i] + lead_s) == marker;
      };
      data.strokes.push_back(
          noisy_stroke(run, times, 2 * r + marker,
                       marker == 1 ? StrokeDirection::kOpening : StrokeDirection::kClosing,
                       in_stroke, noise, random, normal));
    }
  }
  return data;
}

}  // namespace doorbench::testing
