#pragma once
// The residual examination's linearized window simulation (analysis/loop/ only; used by
// residual_examination.cpp): the regressors of the candidate effects, the sensitivities of
// the measured-state windows to them and to the free parameters, their normal equations,
// and the noise floor of the rate residual. docs/residual-loop.md, "The examination".
// Pure functions of their arguments, safe on any thread (each call its own state).
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "analysis/fit/fit_windows.h"
#include "analysis/loop/residual_loop.h"
#include "analysis/model/door_model.h"
#include "analysis/model/effects.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench::loop_detail {

// The base friction of a model's effects (level and speed scale), from its parameters.
effects::BaseFriction<double> base_friction(const DoorModel& model);

// One regressor of the examination: an effect at fixed nonlinear parameters, whose
// amplitude (the first parameter, or d_s − d1 for Stribeck) is free.
struct Regressor {
  effects::Kind kind;
  std::vector<double> unit_values;  // the effect's parameters at amplitude 1
  double amplitude_offset = 0.0;    // parameter 0 = offset + amplitude (Stribeck: d1)
  double lower = 0.0, upper = 0.0;  // the amplitude's range (parameter 0's bounds − offset)
  std::string scan;
};

// The regressors of the candidate effects `kinds`: each at the fixed nonlinear parameters
// of the options' scan grids (Stribeck speeds, soft-close angles and sharpnesses, end-stop
// angles across the data's range of θ), else at its defaults.
std::vector<Regressor> make_regressors(const DoorModel& model, const PreparedData& data,
                                       const std::vector<effects::Kind>& kinds,
                                       const LoopOptions& options);

// The linearized window simulation of one model: the normal equations (Gram matrix) of the
// columns [parameters..., regressors..., e], in total and per window, and Σe².
struct Linearization {
  Eigen::MatrixXd gram;
  std::vector<Eigen::MatrixXd> window_grams;  // each window's share of `gram`
  double rate_sum_of_squares = 0.0;           // Σ(ω − ω̂)², rad²/s²
  std::size_t samples = 0;
  int failed_windows = 0;  // windows whose simulation failed (left out)
  // Σe² and samples per band of measured |ω| (kSpeedBandEdges_rad_s).
  std::array<double, std::size(kSpeedBandEdges_rad_s)> band_sum{}, band_samples{};
  void add_to_band(double measured_rad_s, double error) {
    std::size_t band = std::size(kSpeedBandEdges_rad_s) - 1;
    while (band > 0 && std::abs(measured_rad_s) < kSpeedBandEdges_rad_s[band]) --band;
    band_sum[band] += error * error;
    band_samples[band] += 1.0;
  }
  // The examination's residual by speed (ResidualExamination::speed_bands).
  std::vector<SpeedBand> speed_bands() const {
    std::vector<SpeedBand> bands;
    for (std::size_t b = 0; b < std::size(kSpeedBandEdges_rad_s); ++b) {
      SpeedBand band;
      band.low_rad_s = kSpeedBandEdges_rad_s[b];
      band.high_rad_s = b + 1 < std::size(kSpeedBandEdges_rad_s)
                            ? kSpeedBandEdges_rad_s[b + 1]
                            : std::numeric_limits<double>::infinity();
      band.samples = static_cast<std::size_t>(band_samples[b]);
      band.rms_rad_s = band.samples > 0 ? std::sqrt(band_sum[b] / band_samples[b]) : 0.0;
      bands.push_back(band);
    }
    return bands;
  }
  // The residual's differences along each window, for the noise floor: (e_j − e_{j−1} − d̄)²
  // and (e_j − e_{j−2} − d̄)² (d̄ each window's mean difference), and Σ j over the residuals.
  std::vector<double> lag1_squares, lag2_squares;
  double index_sum = 0.0;
};

// The noise floor from the lag differences (ResidualExamination::noise_floor_rad_s).
void estimate_noise_floor(Linearization& linear, ResidualExamination& examination);

// The linearized window simulation of `model` along the measured-state windows: the
// columns [parameters (model indices)..., regressors..., e] (linearization.cpp says how).
Linearization linearize(const DoorModel& model, const PreparedData& data,
                        const WindowOptions& windows, const std::vector<int>& parameters,
                        const std::vector<Regressor>& regressors);

// Σ(ω − ω̂)² over the windows as linearize() counts it, and the windows that failed, from
// the simulation alone (a trial step's test, without the sensitivities).
std::pair<double, int> window_sum_of_squares(const DoorModel& model, const PreparedData& data,
                                             const WindowOptions& windows);

}  // namespace doorbench::loop_detail
