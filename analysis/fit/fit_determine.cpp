// What would determine a parameter (internal/fit_determine.h; docs/fitting.md, "What would
// determine it"): candidate strokes simulated with the fitted door, and the information their
// windows add to the fit's.
#include "analysis/fit/internal/fit_determine.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/stop_request.h"

namespace doorbench::fit_detail {

namespace {

// One kind of stroke to try: its name and its strokes, simulated with the fitted door.
struct StrokeKind {
  std::string name;
  std::string label;  // the report table's column
  std::vector<Stroke> strokes;
};

// The run's samples [first, end) as one stroke of `direction` (none under 2 samples).
void append_stroke(const Trajectory& run, std::size_t first, std::size_t end,
                   StrokeDirection direction, std::vector<Stroke>& strokes) {
  if (end < first + 2) return;
  Stroke stroke;
  stroke.id = static_cast<int>(strokes.size()) + 1;
  stroke.direction = direction;
  for (std::size_t i = first; i < end; ++i) {
    stroke.time_s.push_back(run.time_s[i]);
    stroke.force_N.push_back(run.force_N[i]);
    stroke.theta_rad.push_back(run.theta_rad[i]);
    stroke.omega_rad_s.push_back(run.omega_rad_s[i]);
  }
  strokes.push_back(std::move(stroke));
}

// The run as an opening up to its largest angle and a closing from there.
void append_opening_and_closing(const Trajectory& run, std::vector<Stroke>& strokes) {
  const auto turn = static_cast<std::size_t>(
      std::max_element(run.theta_rad.begin(), run.theta_rad.end()) - run.theta_rad.begin());
  append_stroke(run, 0, std::min(turn + 1, run.size()), StrokeDirection::kOpening, strokes);
  append_stroke(run, turn, run.size(), StrokeDirection::kClosing, strokes);
}

std::vector<double> sample_times(double end_s, double interval_s) {
  std::vector<double> times;
  for (double t = 0.0; t < end_s; t += interval_s) times.push_back(t);
  return times;
}

// A virtual hand's opening to `target_rad` and closing through the latch, over duration_s.
StrokeKind hand_kind(const std::string& name, const std::string& label, const DoorModel& door,
                     double target_rad, double duration_s, double interval_s) {
  VirtualHandOptions options;
  options.target_angle_rad = target_rad;
  options.duration_s = duration_s;
  const VirtualHand hand(options, door.geometry().handle_radius_m);
  StrokeKind kind{name, label, {}};
  const Trajectory run = simulate(door, hand, DoorState{}, sample_times(duration_s, interval_s));
  append_opening_and_closing(run, kind.strokes);
  return kind;
}

// From rest at each angle, a half-sine push of 0.1 s that sets the door coasting at about
// 0.8 rad/s, open, and one shut from 0.4 rad further (short of the stop): the study's
// impulses, each followed for 2 s.
StrokeKind impulse_kind(const DoorModel& door, const std::vector<double>& angles_rad,
                        double interval_s) {
  std::string name = "impulses at";
  for (std::size_t a = 0; a < angles_rad.size(); ++a) {
    name += (a == 0 ? " " : ", ") + printf_text("%.2g", angles_rad[a]);
  }
  StrokeKind kind{name + " rad, each left to coast", "impulses", {}};
  const double r_h = door.geometry().handle_radius_m;
  constexpr double kPush_s = 0.1, kCoast_s = 2.0, kCoastRate_rad_s = 0.8;
  for (double angle : angles_rad) {
    for (int direction : {1, -1}) {
      const double friction_Nm = std::abs(door.torque_Nm(angle, 0.05 * direction));
      const double impulse_Nm =
          door.inertia_kg_m2() * kCoastRate_rad_s * std::numbers::pi / (2.0 * kPush_s);
      const double peak_N = direction * (impulse_Nm + friction_Nm) / r_h;
      std::vector<double> force_time, force;
      for (double t = 0.0; t <= kPush_s + kCoast_s; t += 0.001) {
        force_time.push_back(t);
        force.push_back(t < kPush_s ? peak_N * std::sin(std::numbers::pi * t / kPush_s) : 0.0);
      }
      const RecordedForce push(std::move(force_time), std::move(force));
      DoorState state;
      state.theta_rad =
          direction > 0 ? angle : std::min(angle + 0.4, door.geometry().theta_max_rad - 0.05);
      try {
        const Trajectory run =
            simulate(door, push, state, sample_times(kPush_s + kCoast_s, interval_s));
        append_stroke(run, 0, run.size(),
                      direction > 0 ? StrokeDirection::kOpening : StrokeDirection::kClosing,
                      kind.strokes);
      } catch (const std::exception&) {
        // A push the door cannot simulate adds no stroke to this kind.
      }
    }
  }
  return kind;
}

// The kinds in the order the report lists them; one the door cannot simulate is left out.
std::vector<StrokeKind> stroke_kinds(const DoorModel& door, double interval_s) {
  const double theta_max = door.geometry().theta_max_rad;
  std::vector<StrokeKind> kinds;
  auto add = [&](auto make) {
    try {
      kinds.push_back(make());
    } catch (const std::exception&) {
      // A run the door cannot simulate is no kind to propose.
    }
  };
  add([&] {
    return hand_kind("slow openings and closings (about 0.1 rad/s)", "slow", door,
                     std::min(1.0, theta_max - 0.1), 30.0, interval_s);
  });
  add([&] {
    return hand_kind("a full-range opening and closing", "full range", door, theta_max - 0.05, 6.0,
                     interval_s);
  });
  add([&] {
    return hand_kind("a latch crossing (open to 0.25 rad and shut through the latch)", "latch",
                     door, 0.25, 4.0, interval_s);
  });
  add([&] {
    std::vector<double> angles;
    for (double a : {0.3, 0.7, 1.1}) {
      if (a < theta_max - 0.2) angles.push_back(a);
    }
    return impulse_kind(door, angles, interval_s);
  });
  return kinds;
}

// Each free parameter's classical relative standard uncertainty from `information` (NaN where
// it lies in an undetermined direction): u / |value|, as the report's table has it, or u / 1 %
// of the bound width at a value of 0.
std::vector<double> relative_uncertainties(const Eigen::MatrixXd& information,
                                           double residual_variance, const ParameterMap& map,
                                           const std::vector<double>& values,
                                           const DoorModel& model) {
  const InformationInverse inverse = invert_information(information);
  const auto bounds = model.parameter_bounds();
  std::vector<double> out(static_cast<std::size_t>(map.free_count()), kNaN);
  for (int k = 0; k < map.free_count(); ++k) {
    if (inverse.undetermined[static_cast<std::size_t>(k)]) continue;
    const int index = map.free_index[static_cast<std::size_t>(k)];
    const double u =
        std::sqrt(std::max(0.0, residual_variance * inverse.inverse(k, k))) * map.scale[k];
    const double width = bounds[index].upper - bounds[index].lower;
    const double reference = values[index] != 0.0   ? std::abs(values[index])
                             : std::isfinite(width) ? 0.01 * width
                                                    : 0.0;
    out[static_cast<std::size_t>(k)] = reference > 0 ? u / reference : kNaN;
  }
  return out;
}

// The sample interval of the candidate strokes: the recording's.
double candidate_interval_s(const PreparedData& data) {
  if (data.interval_median_s > 0) return data.interval_median_s;
  return data.sample_rate_hz > 0 ? 1.0 / data.sample_rate_hz : 0.001;
}

}  // namespace

std::vector<DeterminingStrokes> what_would_determine(const DeterminingInput& input,
                                                     const FitOptions& options,
                                                     const std::vector<int>& positions,
                                                     const std::vector<double>& inflation) {
  std::vector<DeterminingStrokes> rows;
  if (positions.empty()) return rows;
  const std::vector<double> values = input.map.values(input.x.data());
  const double variance = std::isfinite(input.residual_variance) && input.residual_variance > 0
                              ? input.residual_variance
                              : 1.0;
  const std::vector<double> now =
      relative_uncertainties(input.information, variance, input.map, values, input.fitted);
  for (int k : positions) {
    DeterminingStrokes row;
    row.parameter = input.fitted.parameter_name(input.map.free_index[static_cast<std::size_t>(k)]);
    row.relative_now = now[static_cast<std::size_t>(k)] * inflation[rows.size()];
    rows.push_back(std::move(row));
  }
  FitWeights plain = input.weights;
  plain.priors.clear();  // the priors are in `information` already
  for (const StrokeKind& kind : stroke_kinds(input.fitted, candidate_interval_s(input.data))) {
    throw_if_stop_requested(options.stop_requested, "what would determine the parameters");
    if (kind.strokes.empty()) continue;
    PreparedData candidate;
    candidate.source = kind.name;
    candidate.handle_radius_m = input.data.handle_radius_m;
    candidate.sample_rate_hz = input.data.sample_rate_hz;
    candidate.strokes = kind.strokes;
    const WindowProblem problem(input.fitted, candidate, input.map, input.kind, plain, input.x);
    ReducedSystem system;
    if (problem.windows().empty() || !problem.reduce(false, system)) continue;
    const std::vector<double> with = relative_uncertainties(
        input.information + system.information, variance, input.map, values, input.fitted);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const double relative = with[static_cast<std::size_t>(positions[r])] * inflation[r];
      rows[r].kinds.push_back(
          {kind.name, kind.label, relative,
           std::isfinite(relative) && relative <= options.undetermined_relative_uncertainty});
    }
  }
  return rows;
}

}  // namespace doorbench::fit_detail
