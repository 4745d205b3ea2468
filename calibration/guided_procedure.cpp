#include "calibration/guided_procedure.h"

#include <cmath>
#include <istream>
#include <ostream>

#include "calibration/least_squares.h"
#include "calibration/procedure.h"

namespace doorbench::calibration {

std::string GuidedOptions::validate() const {
  if (!(window_s > 0) || !std::isfinite(window_s)) {
    return "guided calibration window_s = " + shortest(window_s) + " must be > 0";
  }
  if (max_windows < 1) {
    return "guided calibration max_windows = " + std::to_string(max_windows) + " must be >= 1";
  }
  if (!(max_std_V > 0))
    return "guided calibration max_std_V = " + shortest(max_std_V) + " must be > 0";
  if (!(max_drift_V > 0)) {
    return "guided calibration max_drift_V = " + shortest(max_drift_V) + " must be > 0";
  }
  return "";
}

namespace {

struct WindowFigures {
  double mean = 0.0, std = 0.0, drift = 0.0;
};

WindowFigures figures_of(const std::vector<double>& window) {
  WindowFigures f;
  f.mean = mean_of(window);
  f.std = std_of(window);
  const std::size_t half = window.size() / 2;
  const std::span<const double> all(window);
  f.drift = std::abs(mean_of(all.subspan(half)) - mean_of(all.first(half)));
  return f;
}

}  // namespace

std::vector<CalibrationPoint> run_guided_points(StaticSignalSource& source,
                                                std::span<const GuidedPoint> points,
                                                const GuidedOptions& options, std::istream& in,
                                                std::ostream& out) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const auto window_samples =
      static_cast<std::size_t>(std::llround(options.window_s * source.sample_rate_hz()));
  if (window_samples < 4) {
    throw CalibrationError("guided calibration: a window of " + shortest(options.window_s) +
                           " s holds fewer than 4 samples at " + shortest(source.sample_rate_hz()) +
                           " Hz");
  }
  auto shown = [&](double volts, int decimals) {
    return fixed(volts * options.display_per_V, decimals) + " " + options.display_unit;
  };
  out << "Calibrating " << source.description() << ": " << points.size()
      << " points, each the mean of a stable " << shortest(options.window_s) << " s window.\n";
  std::vector<CalibrationPoint> result;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const GuidedPoint& point = points[i];
    const std::string which = "point " + std::to_string(i + 1) + " of " +
                              std::to_string(points.size()) + " (" + point.label +
                              (point.branch.empty() ? "" : ", " + point.branch) + ")";
    out << "[" << i + 1 << "/" << points.size() << "] " << point.instruction
        << ", then press Enter (q to quit): " << std::flush;
    std::string answer;
    if (!std::getline(in, answer)) {
      out << "\n";
      throw CalibrationError("calibration aborted at " + which + ": the input ended");
    }
    if (answer == "q" || answer == "Q") {
      throw CalibrationError("calibration aborted by the operator at " + which);
    }
    source.expect_reference(point.reference);
    WindowFigures last;
    bool stable = false;
    std::vector<double> window;
    for (int attempt = 1; attempt <= options.max_windows && !stable; ++attempt) {
      window = source.read_V(window_samples);
      last = figures_of(window);
      stable = last.std <= options.max_std_V && last.drift <= options.max_drift_V;
      if (!stable) {
        out << "  not yet stable (window " << attempt << "/" << options.max_windows << ": sd "
            << shown(last.std, 4) << ", drift " << shown(last.drift, 4) << ")\n";
      }
    }
    if (!stable) {
      throw CalibrationError(
          "the reading did not settle at " + which + ": in each of " +
          std::to_string(options.max_windows) + " windows of " + shortest(options.window_s) +
          " s the standard deviation or drift was above its limit (last window: sd " +
          shown(last.std, 4) + ", limit " + shown(options.max_std_V, 4) + "; drift " +
          shown(last.drift, 4) + ", limit " + shown(options.max_drift_V, 4) +
          "); steady the reference (no swinging load, no touching) and repeat");
    }
    CalibrationPoint p;
    p.reference = point.reference;
    p.signal = last.mean;
    p.signal_std = last.std;
    p.samples = static_cast<int>(window.size());
    p.branch = point.branch;
    out << "  " << point.label << ": " << fixed(p.signal, 5) << " V, sd " << fixed(p.signal_std, 5)
        << " V (" << shown(p.signal_std, 4) << ") over " << p.samples << " samples\n";
    result.push_back(p);
  }
  return result;
}

}  // namespace doorbench::calibration
