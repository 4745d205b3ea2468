#include "analysis/simulation/fit_synthetic.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"
#include "core/units.h"

namespace doorbench {

PreparedData synthetic_strokes(const DoorModel& model, const SyntheticStrokeOptions& options) {
  if (!(options.sample_rate_hz > 0) || options.runs.empty()) {
    throw std::invalid_argument("synthetic strokes need runs and a sample rate > 0");
  }
  PreparedData data;
  data.source = "synthetic";
  data.handle_radius_m = model.geometry().handle_radius_m;
  data.sample_rate_hz = options.sample_rate_hz;
  data.rate_noise_rad_s =
      options.rate_noise_rad_s > 0 ? options.rate_noise_rad_s : 0.05 * kRadPerDeg;
  data.angle_noise_rad = options.angle_noise_rad > 0 ? options.angle_noise_rad : 0.01 * kRadPerDeg;

  std::mt19937 random(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double r_h = model.geometry().handle_radius_m;
  for (std::size_t r = 0; r < options.runs.size(); ++r) {
    VirtualHandOptions hand_options;
    hand_options.target_angle_rad = options.runs[r].target_angle_rad;
    hand_options.duration_s = options.runs[r].duration_s;
    const VirtualHand hand(hand_options, r_h);
    const SampledRun sampled =
        simulate_sampled_run(model, hand, hand_options.duration_s, options.sample_rate_hz);
    const std::vector<double>& times = sampled.times_s;
    const Trajectory& run = sampled.run;

    const SampleNoise noise{options.force_noise_N, options.angle_noise_rad,
                            options.rate_noise_rad_s};
    for (int marker : {1, 2}) {
      data.strokes.push_back(noisy_stroke(
          run, times, static_cast<int>(2 * r) + marker,
          marker == 1 ? StrokeDirection::kOpening : StrokeDirection::kClosing,
          [&](std::size_t i) { return hand.stroke_at(times[i]) == marker; }, noise, random,
          normal));
    }
  }
  return data;
}

SampledRun simulate_sampled_run(const DoorModel& model, const UserForce& hand, double duration_s,
                                double sample_rate_hz) {
  const auto samples = static_cast<std::size_t>(std::floor(duration_s * sample_rate_hz));
  SampledRun sampled;
  sampled.times_s.resize(samples + 1);
  for (std::size_t i = 0; i <= samples; ++i) {
    sampled.times_s[i] = static_cast<double>(i) / sample_rate_hz;
  }
  const Trajectory by_hand = simulate(model, hand, DoorState{}, sampled.times_s);
  const RecordedForce recorded(sampled.times_s, by_hand.force_N);
  sampled.run = simulate(model, recorded, DoorState{}, sampled.times_s);
  return sampled;
}

Stroke noisy_stroke(const Trajectory& run, const std::vector<double>& times, int id,
                    StrokeDirection direction, const std::function<bool(std::size_t)>& in_stroke,
                    const SampleNoise& noise, std::mt19937& random,
                    std::normal_distribution<double>& normal) {
  Stroke stroke;
  stroke.id = id;
  stroke.direction = direction;
  for (std::size_t i = 0; i < run.size(); ++i) {
    if (!in_stroke(i)) continue;
    stroke.time_s.push_back(times[i]);
    stroke.force_N.push_back(run.force_N[i] + noise.force_N * normal(random));
    stroke.theta_rad.push_back(run.theta_rad[i] + noise.angle_rad * normal(random));
    stroke.omega_rad_s.push_back(run.omega_rad_s[i] + noise.rate_rad_s * normal(random));
  }
  return stroke;
}

}  // namespace doorbench
