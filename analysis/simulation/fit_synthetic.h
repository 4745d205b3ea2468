#pragma once
// Synthetic prepared strokes for tests, benchmarks and demos of the fit: a door model
// opened and closed by the virtual hand, once per run (several target angles and
// durations, so that the data excite every part of the model), with the bench's noise.
//
// Each run is simulated twice: first under the virtual hand, whose force is sampled at the
// sample rate; then again from the same initial state under that sampled force, linearly
// interpolated (RecordedForce). The second trajectory is the data: it is exactly what a
// model driven by the recorded force does, so a noise-free fit at the true parameters
// leaves only the integrators' error. Gaussian noise is added afterwards to the force,
// angle and rate, as a bench's sensors would.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"
#include "analysis/simulation/simulator.h"
#include "core/units.h"

namespace doorbench {

struct SyntheticRun {
  double target_angle_rad = 1.0;
  double duration_s = 4.0;  // the virtual hand's whole run (rest, opening, pause, closing)
};

struct SyntheticStrokeOptions {
  std::vector<SyntheticRun> runs = {{0.6, 3.0}, {1.0, 4.0}, {1.3, 5.0}};
  double sample_rate_hz = 1000.0;
  // Standard deviations of the Gaussian noise added; the bench's figures by default.
  double force_noise_N = 0.2;
  double angle_noise_rad = 0.01 * kRadPerDeg;
  double rate_noise_rad_s = 0.05 * kRadPerDeg;
  std::uint32_t seed = 1;
};

// Two strokes per run, the opening (id 2r + 1) and the closing through the hold (2r + 2),
// as the virtual hand marks them. The data's noise levels are the options' (the bench's
// where an option is 0, so that a noise-free fit keeps sensible weights).
PreparedData synthetic_strokes(const DoorModel& model, const SyntheticStrokeOptions& options);

// The sample times 0, 1/rate, ... up to duration_s (floor), and the run the data are made
// of: the door simulated under `hand`, then again from rest under that force as sampled
// at those times (RecordedForce), as the comment at the top of this file explains.
struct SampledRun {
  std::vector<double> times_s;
  Trajectory run;
};
SampledRun simulate_sampled_run(const DoorModel& model, const UserForce& hand, double duration_s,
                                double sample_rate_hz);

// Standard deviations of the white noise a bench's sensors add.
struct SampleNoise {
  double force_N = 0.0;
  double angle_rad = 0.0;
  double rate_rad_s = 0.0;
};

// One stroke of a simulated run as a bench would record it: the samples i of `run` (at
// `times`) for which in_stroke(i) holds, each with Gaussian noise drawn from `normal` and
// `random` in the order force, angle, rate (the same draws for the same generator state).
Stroke noisy_stroke(const Trajectory& run, const std::vector<double>& times, int id,
                    StrokeDirection direction, const std::function<bool(std::size_t)>& in_stroke,
                    const SampleNoise& noise, std::mt19937& random,
                    std::normal_distribution<double>& normal);

}  // namespace doorbench
