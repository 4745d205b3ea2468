#include "analysis/fit/fit_start.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/fit/fit_windows.h"
#include "analysis/model/sensory_model.h"
#include "core/numbers.h"
#include "core/percentile.h"

namespace doorbench {

std::vector<double> rate_derivative(const Stroke& stroke, double half_width_s) {
  const int n = static_cast<int>(stroke.size());
  std::vector<double> derivative(n, 0.0);
  // Piece by piece between the recording's gaps: no difference spans one.
  std::vector<int> ends = stroke_gaps(stroke);
  ends.push_back(n);
  int begin = 0;
  for (const int end : ends) {
    for (int i = begin; i < end; ++i) {
      // At least one sample each side; more while they lie within the half width.
      int lo = std::max(begin, i - 1), hi = std::min(end - 1, i + 1);
      while (lo > begin && stroke.time_s[i] - stroke.time_s[lo - 1] <= half_width_s) --lo;
      while (hi < end - 1 && stroke.time_s[hi + 1] - stroke.time_s[i] <= half_width_s) ++hi;
      if (hi > lo) {
        derivative[i] = (stroke.omega_rad_s[hi] - stroke.omega_rad_s[lo]) /
                        (stroke.time_s[hi] - stroke.time_s[lo]);
      }
    }
    begin = end;
  }
  return derivative;
}

namespace {

constexpr int kHingeGrid = 40;  // points per scan (two scans: coarse, fine)
constexpr std::size_t kMinimumRampSamples = 10;
// dω/dt where the peaks are read: the shortest central difference. The latch's events
// last a few milliseconds; a wider difference smears the torque along the angle by ω
// times its width.
constexpr double kPeakHalfWidth_s = 0.001;
// dω/dt as a regressor on the ramps, where the door creeps: smoother, so that its noise
// does not bias the fit (errors in a regressor shrink its coefficient).
constexpr double kRampHalfWidth_s = 0.005;

// Samples of the ramp: the hand's torque y = r_h F against the angle x, with dω/dt.
struct Ramp {
  std::vector<double> angle, torque, acceleration;
  std::size_t size() const { return angle.size(); }
};

// Least squares of y ≈ a + b (x − knot) + c h(x) [+ J dω/dt], h the hinge (x − knot)_+ or
// (knot − x)_+: the latch's torque as two lines meeting at the knot, and the inertia when
// the ramp's accelerations are given.
struct HingeFit {
  double sse = kNaN;
  double slope_change = kNaN;  // c
  double inertia = kNaN;       // J
};

HingeFit fit_hinge(const Ramp& ramp, double knot, bool hinge_above) {
  const bool with_inertia = !ramp.acceleration.empty();
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Vector4d right = Eigen::Vector4d::Zero();
  auto row = [&](std::size_t i) {
    const double x = ramp.angle[i];
    const double hinge = hinge_above ? std::max(0.0, x - knot) : std::max(0.0, knot - x);
    return Eigen::Vector4d(1.0, x - knot, hinge, with_inertia ? ramp.acceleration[i] : 0.0);
  };
  for (std::size_t i = 0; i < ramp.size(); ++i) {
    const Eigen::Vector4d r = row(i);
    normal += r * r.transpose();
    right += r * ramp.torque[i];
  }
  Eigen::Vector4d coefficient = Eigen::Vector4d::Zero();
  if (with_inertia) {
    const Eigen::LDLT<Eigen::Matrix4d> solver(normal);
    if (solver.info() != Eigen::Success) return {};
    coefficient = solver.solve(right);
  } else {
    const Eigen::LDLT<Eigen::Matrix3d> solver(normal.topLeftCorner<3, 3>());
    if (solver.info() != Eigen::Success) return {};
    coefficient.head<3>() = solver.solve(right.head<3>());
  }
  if (!coefficient.allFinite()) return {};
  HingeFit fit;
  fit.sse = 0.0;
  for (std::size_t i = 0; i < ramp.size(); ++i) {
    const double error = ramp.torque[i] - row(i).dot(coefficient);
    fit.sse += error * error;
  }
  fit.slope_change = coefficient(2);
  if (with_inertia) fit.inertia = coefficient(3);
  return fit;
}

struct Knot {
  double at = kNaN;
  HingeFit fit;
};

// The knot in (lo, hi) that fits best: on a coarse uniform grid, then on a fine one around
// the coarse best.
Knot best_knot(const Ramp& ramp, double lo, double hi, bool hinge_above) {
  Knot best;
  double best_sse = std::numeric_limits<double>::infinity();
  auto scan = [&](double from, double to) {
    for (int g = 1; g < kHingeGrid; ++g) {
      const double knot = from + (to - from) * g / kHingeGrid;
      const HingeFit fit = fit_hinge(ramp, knot, hinge_above);
      if (fit.sse < best_sse) {
        best_sse = fit.sse;
        best = {knot, fit};
      }
    }
  };
  scan(lo, hi);
  if (std::isfinite(best.at)) {
    const double step = (hi - lo) / kHingeGrid;
    scan(std::max(lo, best.at - step), std::min(hi, best.at + step));
  }
  return best;
}

struct Context {
  double handle_radius_m;
  double inertia_kg_m2;  // the start's J, used where the ramp's own estimate is not usable
  double beta;
  double zone_rad;  // the latch region read: θ below this
  double moving_rad_s;
};

// The ramp's J when it is plausible (within a factor 3 of the start's), else the start's.
double usable_inertia(const HingeFit& fit, const Context& context) {
  const double ratio = fit.inertia / context.inertia_kg_m2;
  return ratio > 1.0 / 3.0 && ratio < 3.0 ? fit.inertia : context.inertia_kg_m2;
}

struct OpeningReading {
  double theta0, theta1, k_inf, inertia;
};

std::optional<OpeningReading> read_opening(const Stroke& stroke, const Context& context) {
  const int n = static_cast<int>(stroke.size());
  if (n < 3 || !(stroke.theta_rad[0] < 0.5 * context.zone_rad)) return std::nullopt;
  int end = 0;
  while (end < n && stroke.theta_rad[end] <= context.zone_rad) ++end;
  if (end == n) return std::nullopt;  // never left the latch region: it did not unlatch
  const std::vector<double> acceleration = rate_derivative(stroke, kPeakHalfWidth_s);
  const std::vector<double> smooth_acceleration = rate_derivative(stroke, kRampHalfWidth_s);
  const double r_h = context.handle_radius_m;
  // The resistance R = r_h F − J dω/dt peaks where the latch releases.
  auto peak_of = [&](double inertia) {
    int peak = 0;
    double largest = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < end; ++i) {
      const double resistance = r_h * stroke.force_N[i] - inertia * acceleration[i];
      if (resistance > largest) {
        largest = resistance;
        peak = i;
      }
    }
    return peak;
  };
  const double width = 1.0 / context.beta;  // half a switch's 4/β width is 2/β
  auto ramp_before = [&](int peak) {
    Ramp ramp;
    for (int i = 0; i < peak; ++i) {
      if (stroke.omega_rad_s[i] > context.moving_rad_s &&
          stroke.theta_rad[i] <= stroke.theta_rad[peak] - width) {
        ramp.angle.push_back(stroke.theta_rad[i]);
        ramp.torque.push_back(r_h * stroke.force_N[i]);
        ramp.acceleration.push_back(smooth_acceleration[i]);
      }
    }
    return ramp;
  };
  int peak = peak_of(context.inertia_kg_m2);
  Ramp ramp = ramp_before(peak);
  if (ramp.size() < kMinimumRampSamples) return std::nullopt;
  double lowest = *std::min_element(ramp.angle.begin(), ramp.angle.end());
  Knot knot = best_knot(ramp, lowest, stroke.theta_rad[peak] - width, /*hinge_above=*/true);
  if (!std::isfinite(knot.at)) return std::nullopt;
  // Again with the ramp's own J for the peak.
  peak = peak_of(usable_inertia(knot.fit, context));
  ramp = ramp_before(peak);
  if (ramp.size() < kMinimumRampSamples) return std::nullopt;
  const double theta_peak = stroke.theta_rad[peak];
  lowest = *std::min_element(ramp.angle.begin(), ramp.angle.end());
  if (!(theta_peak - width > lowest)) return std::nullopt;
  knot = best_knot(ramp, lowest, theta_peak - width, /*hinge_above=*/true);
  if (!(knot.fit.slope_change > 0) || !std::isfinite(knot.at)) return std::nullopt;
  // k_inf (θ − θ0) S̄(θ; θ1, β) peaks at θ1 − ln(2β (θ − θ0) − 1) / (2β).
  const double lever = 2.0 * context.beta * (theta_peak - knot.at) - 1.0;
  const double theta1 = theta_peak + std::log(std::max(lever, 1.0)) / (2.0 * context.beta);
  return OpeningReading{.theta0 = knot.at,
                        .theta1 = theta1,
                        .k_inf = knot.fit.slope_change,
                        .inertia = usable_inertia(knot.fit, context)};
}

struct ClosingReading {
  double theta2, theta3, k_lock;
};

// `inertia`: J from the opening ramps (or the start's). The closing ramp is fitted without
// a J column: the door meets the latch with speed, and the accelerations there are too
// brief and too noisy for a regressor.
std::optional<ClosingReading> read_closing(const Stroke& stroke, const Context& context,
                                           double floor_rad, double inertia) {
  const int n = static_cast<int>(stroke.size());
  if (n < 3) return std::nullopt;
  int begin = n - 1;
  while (begin >= 0 && stroke.theta_rad[begin] <= context.zone_rad) --begin;
  if (begin < 0) return std::nullopt;  // never above the latch region
  ++begin;
  const std::vector<double> acceleration = rate_derivative(stroke, kPeakHalfWidth_s);
  const double r_h = context.handle_radius_m;
  // The mechanism's torque τ_m = J dω/dt − r_h F (pushing the door open) peaks near θ2.
  auto peak_of = [&](double inertia) {
    int peak = -1;
    double largest = -std::numeric_limits<double>::infinity();
    for (int i = begin; i < n; ++i) {
      const double torque = inertia * acceleration[i] - r_h * stroke.force_N[i];
      if (stroke.theta_rad[i] > floor_rad && torque > largest) {
        largest = torque;
        peak = i;
      }
    }
    return peak;
  };
  const int peak = peak_of(inertia);
  if (peak < 0) return std::nullopt;
  const double theta_peak = stroke.theta_rad[peak];
  const double width = 1.0 / context.beta;
  Ramp ramp;  // τ_m = J dω/dt − r_h F against θ
  for (int i = begin; i < peak; ++i) {
    if (stroke.omega_rad_s[i] < -context.moving_rad_s &&
        stroke.theta_rad[i] >= theta_peak + width) {
      ramp.angle.push_back(stroke.theta_rad[i]);
      ramp.torque.push_back(inertia * acceleration[i] - r_h * stroke.force_N[i]);
    }
  }
  if (ramp.size() < kMinimumRampSamples) return std::nullopt;
  const double highest = *std::max_element(ramp.angle.begin(), ramp.angle.end());
  if (!(highest > theta_peak + width)) return std::nullopt;
  const Knot knot = best_knot(ramp, theta_peak + width, highest, /*hinge_above=*/false);
  const double k_lock = knot.fit.slope_change;
  if (!(k_lock > 0) || !std::isfinite(knot.at)) return std::nullopt;
  // A knot less than 2/β above the peak (half a switch's width; its search begins at 1/β) is no
  // latching zone: the torque rises only at its peak, as where a hand stops the door short of
  // the latch.
  if (knot.at < theta_peak + 2.0 * width) return std::nullopt;
  // k_lock (θ3 − θ) S(θ; θ2, β) peaks at θ2 + ln(2β (θ3 − θ) − 1) / (2β).
  const double lever = 2.0 * context.beta * (knot.at - theta_peak) - 1.0;
  const double theta2 = theta_peak - std::log(std::max(lever, 1.0)) / (2.0 * context.beta);
  return ClosingReading{theta2, knot.at, k_lock};
}

}  // namespace

LatchReadOff read_latch_start(const PreparedData& data, const DoorModel& start,
                              double rate_noise_rad_s) {
  LatchReadOff out;
  if (start.kind() != ModelKind::kSensory) {
    out.notes.push_back("the latch is read off the data for the sensory model only");
    return out;
  }
  const auto values = start.parameter_values();
  Context context;
  context.handle_radius_m = start.geometry().handle_radius_m;
  context.inertia_kg_m2 = start.inertia_kg_m2();
  context.beta = values[sensory::kBeta];
  // The latch region: a few times the start's θ3, at least 0.12 rad (about 7°), never
  // beyond half the range.
  context.zone_rad = std::min(std::max(0.12, 2.0 * values[sensory::kTheta3]),
                              0.5 * start.geometry().theta_max_rad);
  context.moving_rad_s = 3.0 * rate_noise_rad_s;

  std::vector<double> theta0, theta1, k_inf, inertia, theta2, theta3, k_lock;
  for (const Stroke& stroke : data.strokes) {
    if (stroke.direction != StrokeDirection::kOpening) continue;
    if (const auto reading = read_opening(stroke, context)) {
      theta0.push_back(reading->theta0);
      theta1.push_back(reading->theta1);
      k_inf.push_back(reading->k_inf);
      inertia.push_back(reading->inertia);
    }
  }
  out.opening_strokes = static_cast<int>(theta1.size());
  if (!theta1.empty()) {
    out.theta0_rad = median(theta0);
    out.theta1_rad = median(theta1);
    out.k_inf_Nm_per_rad = median(k_inf);
  } else {
    out.notes.push_back("no opening stroke unlatches from closed: theta0, theta1, k_inf not read");
  }
  // Below θ1 the snap and the unlatching pull the door shut and the cabinet stop pushes
  // back: the closing peak is looked for above.
  const double floor_rad = 0.5 * out.theta1_rad.value_or(values[sensory::kTheta1]);
  for (const Stroke& stroke : data.strokes) {
    if (stroke.direction != StrokeDirection::kClosing) continue;
    const double ramp_inertia = inertia.empty() ? context.inertia_kg_m2 : median(inertia);
    if (const auto reading = read_closing(stroke, context, floor_rad, ramp_inertia)) {
      theta2.push_back(reading->theta2);
      theta3.push_back(reading->theta3);
      k_lock.push_back(reading->k_lock);
    }
  }
  out.closing_strokes = static_cast<int>(theta2.size());
  if (!theta2.empty()) {
    out.theta2_rad = median(theta2);
    out.theta3_rad = median(theta3);
    out.k_lock_Nm_per_rad = median(k_lock);
  } else {
    out.notes.push_back(
        "no closing stroke latches from above the latch region: theta2, theta3, k_lock not read");
  }
  return out;
}

}  // namespace doorbench
