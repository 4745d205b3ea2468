#include "haptic/safety.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "core/number_format.h"

namespace doorbench::haptic {
namespace {

// A clipping episode ends after this many ticks without clipping; only then may the same
// clipping event be raised again (so a limit that acts every other tick makes one event).
constexpr int kQuietTicksBeforeReraise = 100;

bool positive_finite(double value) {
  return value > 0.0 && std::isfinite(value);
}

// |v| without overflow for huge finite components; +inf when a component is not finite.
double safe_norm(const Vec3& v) noexcept {
  if (!v.allFinite()) return INFINITY;
  const double largest = v.cwiseAbs().maxCoeff();
  if (largest == 0.0) return 0.0;
  return largest * (v / largest).norm();
}

std::string three_digits(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

std::string option_problem(const char* name, double value, const char* requirement) {
  return std::string(name)
      .append(" = ")
      .append(format_number(value))
      .append(" ")
      .append(requirement);
}

}  // namespace

std::string SafetyOptions::validate() const {
  if (!positive_finite(max_force)) return option_problem("max_force", max_force, "must be > 0");
  if (!positive_finite(max_force_rate)) {
    return option_problem("max_force_rate", max_force_rate, "must be > 0");
  }
  if (!positive_finite(velocity_trip)) {
    return option_problem("velocity_trip", velocity_trip, "must be > 0");
  }
  if (!(workspace_margin_m >= 0.0) || !std::isfinite(workspace_margin_m)) {
    return option_problem("workspace_margin_m", workspace_margin_m, "must be >= 0");
  }
  if (!(startup_ramp_s >= 0.0) || !std::isfinite(startup_ramp_s)) {
    return option_problem("startup_ramp_s", startup_ramp_s, "must be >= 0");
  }
  if (!positive_finite(shutdown_ramp_s)) {
    return option_problem("shutdown_ramp_s", shutdown_ramp_s, "must be > 0");
  }
  if (!positive_finite(max_tick_interval_s)) {
    return option_problem("max_tick_interval_s", max_tick_interval_s, "must be > 0");
  }
  if (!positive_finite(max_tick_stall_s)) {
    return option_problem("max_tick_stall_s", max_tick_stall_s, "must be > 0");
  }
  if (max_stale_ticks < 1) {
    return std::string("max_stale_ticks = ")
        .append(std::to_string(max_stale_ticks))
        .append(" must be >= 1");
  }
  return "";
}

std::string_view to_string(SafetyState state) {
  switch (state) {
    case SafetyState::kStarting:
      return "starting";
    case SafetyState::kRunning:
      return "running";
    case SafetyState::kRampingDown:
      return "ramping_down";
    case SafetyState::kStopped:
      return "stopped";
  }
  return "";
}

std::string_view event_name(std::uint32_t single_event_bit) {
  switch (single_event_bit) {
    case kEventStartRampDone:
      return "start_ramp_done";
    case kEventForceLimited:
      return "force_limited";
    case kEventForceRateLimited:
      return "force_rate_limited";
    case kEventVelocityTrip:
      return "velocity_trip";
    case kEventWorkspaceTrip:
      return "workspace_trip";
    case kEventDeadlineMiss:
      return "deadline_miss";
    case kEventLateTick:
      return "late_tick";
    case kEventDeviceStalled:
      return "device_stalled";
    case kEventLinkLost:
      return "link_lost";
    case kEventNonFiniteInput:
      return "non_finite_input";
    case kEventPassivityActive:
      return "passivity_active";
    case kEventStopRequested:
      return "stop_requested";
    case kEventStopped:
      return "stopped";
    default:
      return "";
  }
}

std::string_view event_meaning(std::uint32_t single_event_bit) {
  switch (single_event_bit) {
    case kEventStartRampDone:
      return "the start-up ramp reached full force";
    case kEventForceLimited:
      return "the commanded force reached the force limit (the smaller of the device's and "
             "max_force) and was clipped";
    case kEventForceRateLimited:
      return "the commanded force changed faster than the rate limit (the smaller of the "
             "device's and max_force_rate) and was slowed";
    case kEventVelocityTrip:
      return "trip: the device moved faster than velocity_trip (or the device's max_velocity)";
    case kEventWorkspaceTrip:
      return "trip: the device left its workspace less workspace_margin_m";
    case kEventDeadlineMiss:
      return "trip: the time between two ticks exceeded max_tick_stall_s (or went backwards)";
    case kEventLateTick:
      return "a tick came more than max_tick_interval_s after the previous one: the device held "
             "the last force meanwhile; counted, playback goes on";
    case kEventDeviceStalled:
      return "trip: the device's sample did not change for max_stale_ticks ticks";
    case kEventLinkLost:
      return "trip: the device reported its link lost";
    case kEventNonFiniteInput:
      return "trip: a time, reading or desired force was NaN or infinite";
    case kEventPassivityActive:
      return "the energy injected by the model's active terms exceeded the budget: the "
             "passivity controller added damping";
    case kEventStopRequested:
      return "stop requested: ramping the force down";
    case kEventStopped:
      return "the force reached zero after a trip or a stop; the layer holds it at zero";
    default:
      return "";
  }
}

std::string SafetyLayer::describe(std::uint32_t single_event_bit, const EventFacts& facts) const {
  const bool rotary = limits_.kinematics == Kinematics::kRotary1;
  const auto figure = [](double value) { return format_significant(value, 3); };
  const DeviceSample& sample = facts.sample;
  std::string text = std::string(event_name(single_event_bit)).append(": ");
  switch (single_event_bit) {
    case kEventVelocityTrip: {
      const double speed = rotary ? std::abs(sample.velocity.x()) : safe_norm(sample.velocity);
      const char* unit = rotary ? " rad/s" : " m/s";
      return text.append("the device moved at ")
          .append(figure(speed))
          .append(unit)
          .append(", above the trip speed of ")
          .append(figure(velocity_trip_))
          .append(unit)
          .append(" (velocity_trip, or the device's max_velocity)");
    }
    case kEventWorkspaceTrip: {
      const double margin = options_.workspace_margin_m;
      const char* axes[3] = {"x", "y", "z"};
      for (int axis = 0; axis < (rotary ? 1 : 3); ++axis) {
        const double low = limits_.workspace_min[axis] + margin;
        const double high = limits_.workspace_max[axis] - margin;
        const double at = sample.position[axis];
        if (at >= low && at <= high) continue;
        const char* unit = rotary ? " rad" : " m";
        const double bound = at < low ? low : high;
        return text
            .append(rotary ? "the device's angle" : std::string("the device's ") + axes[axis])
            .append(" reached ")
            .append(format_significant(at, 4))
            .append(unit)
            .append(", ")
            .append(figure(std::abs(at - bound) * 1e3))
            .append(rotary ? " mrad" : " mm")
            .append(" beyond ")
            .append(format_significant(bound, 4))
            .append(unit)
            .append(" (its workspace less workspace_margin_m ")
            .append(figure(margin))
            .append(" m)");
      }
      break;
    }
    case kEventDeadlineMiss:
      if (!(facts.interval_s >= 0.0)) break;
      return text.append(figure(facts.interval_s))
          .append(" s between two ticks, above max_tick_stall_s ")
          .append(figure(options_.max_tick_stall_s))
          .append(" s: the tick stalled");
    case kEventLateTick:
      if (!(facts.interval_s >= 0.0)) break;
      return text.append(figure(facts.interval_s * 1e3))
          .append(" ms between two ticks, above max_tick_interval_s ")
          .append(figure(options_.max_tick_interval_s * 1e3))
          .append(" ms: the device held the last force meanwhile; counted, playback goes on");
    case kEventDeviceStalled:
      return text.append("the device's reading did not change for ")
          .append(std::to_string(facts.stale_ticks))
          .append(" ticks (max_stale_ticks ")
          .append(std::to_string(options_.max_stale_ticks))
          .append(")");
    default:
      break;
  }
  return text.append(event_meaning(single_event_bit));
}

SafetyLayer::SafetyLayer(const SafetyOptions& options, const DeviceLimits& limits)
    : options_(options), limits_(limits) {
  if (std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("safety options: ").append(problem));
  }
  if (!positive_finite(limits_.max_force)) {
    throw std::invalid_argument(
        std::string("device limits: ")
            .append(option_problem("max_force", limits_.max_force, "must be > 0")));
  }
  if (!positive_finite(limits_.max_force_rate)) {
    throw std::invalid_argument(
        std::string("device limits: ")
            .append(option_problem("max_force_rate", limits_.max_force_rate, "must be > 0")));
  }
  if (!positive_finite(limits_.max_velocity)) {
    throw std::invalid_argument(
        std::string("device limits: ")
            .append(option_problem("max_velocity", limits_.max_velocity, "must be > 0")));
  }
  if (!limits_.workspace_min.allFinite() || !limits_.workspace_max.allFinite()) {
    throw std::invalid_argument("device limits: the workspace must be finite");
  }
  force_limit_ = std::min(options_.max_force, limits_.max_force);
  force_rate_limit_ = std::min(options_.max_force_rate, limits_.max_force_rate);
  velocity_trip_ = std::min(options_.velocity_trip, limits_.max_velocity);
  // The ramp down scales the force at the trip linearly to zero; it must not be steeper than
  // the rate limit, or the two promises would contradict each other.
  if (force_limit_ / force_rate_limit_ > options_.shutdown_ramp_s) {
    throw std::invalid_argument(
        std::string("safety options: shutdown_ramp_s = ")
            .append(format_number(options_.shutdown_ramp_s))
            .append(" is shorter than the force limit over the rate limit (")
            .append(format_number(force_limit_))
            .append(" / ")
            .append(format_number(force_rate_limit_))
            .append(" s): the rate limit could not bring the force to zero in time"));
  }
}

void SafetyLayer::request_stop() noexcept {
  stop_requested_ = true;
}

SafetyOutput SafetyLayer::stopped_output(std::uint32_t events) noexcept {
  state_ = SafetyState::kStopped;
  scale_ = 0.0;
  previous_force_ = Vec3::Zero();
  SafetyOutput output;
  output.force = Vec3::Zero();
  output.scale = 0.0;
  output.events = events;
  output.state = state_;
  return output;
}

void SafetyLayer::begin_ramp_down(double time_s, std::uint32_t event,
                                  SafetyOutput& output) noexcept {
  output.events |= event;
  if (state_ == SafetyState::kRampingDown) return;
  state_ = SafetyState::kRampingDown;
  ramp_down_start_s_ = time_s;
  ramp_down_from_force_ = previous_force_;
  ramp_down_from_scale_ = scale_;
  ramp_down_remaining_ = 1.0;
}

SafetyOutput SafetyLayer::step(const SafetyInput& input) noexcept {
  if (state_ == SafetyState::kStopped) return stopped_output(0);
  const double time_s = input.time_s;
  // Without a clock there is no ramp: the one case where the force drops to zero at once.
  if (!std::isfinite(time_s)) return stopped_output(kEventNonFiniteInput | kEventStopped);

  SafetyOutput output;
  const bool first_tick = !have_previous_;
  const double dt_s = advance_clock(time_s, input.sample.sequence);
  if (state_ != SafetyState::kRampingDown) check_trips(input, first_tick, dt_s, output);
  if (state_ == SafetyState::kRampingDown) return ramp_down(time_s, output);
  // Starting or running.
  if (state_ == SafetyState::kStarting) advance_start_ramp(time_s, output);
  bool force_clipped = false;
  bool rate_clipped = false;
  const Vec3 target = limit_force(input.desired_force, dt_s, force_clipped, rate_clipped);
  report_clipping(force_clipped, rate_clipped, output);
  previous_force_ = target;
  output.force = target;
  output.scale = scale_;
  output.state = state_;
  output.clipped = force_clipped || rate_clipped;
  return output;
}

double SafetyLayer::advance_clock(double time_s, std::uint64_t sequence) noexcept {
  double dt_s = 0.0;
  if (!have_previous_) {
    have_previous_ = true;
    start_time_s_ = time_s;
    previous_sequence_ = sequence;
  } else {
    dt_s = time_s - previous_time_s_;
  }
  previous_time_s_ = time_s;
  return dt_s;
}

void SafetyLayer::check_trips(const SafetyInput& input, bool first_tick, double dt_s,
                              SafetyOutput& output) noexcept {
  const double time_s = input.time_s;
  const DeviceSample& sample = input.sample;
  if (!first_tick && (dt_s > options_.max_tick_stall_s || dt_s < 0.0)) {
    begin_ramp_down(time_s, kEventDeadlineMiss, output);
  } else if (!first_tick && dt_s > options_.max_tick_interval_s) {
    output.events |= kEventLateTick;
  }
  if (!sample.link_ok) begin_ramp_down(time_s, kEventLinkLost, output);
  if (!first_tick) check_stale(time_s, sample.sequence, output);
  const bool finite_sample = sample.position.allFinite() && sample.velocity.allFinite() &&
                             sample.measured_force.allFinite();
  if (!finite_sample || !input.desired_force.allFinite()) {
    begin_ramp_down(time_s, kEventNonFiniteInput, output);
  }
  if (finite_sample) check_motion(time_s, sample, output);
  if (stop_requested_ && !stop_reported_) {
    stop_reported_ = true;
    begin_ramp_down(time_s, kEventStopRequested, output);
  }
}

void SafetyLayer::check_stale(double time_s, std::uint64_t sequence,
                              SafetyOutput& output) noexcept {
  if (sequence == previous_sequence_) {
    ++stale_ticks_;
  } else {
    stale_ticks_ = 0;
    previous_sequence_ = sequence;
  }
  if (stale_ticks_ >= options_.max_stale_ticks) {
    begin_ramp_down(time_s, kEventDeviceStalled, output);
  }
}

void SafetyLayer::check_motion(double time_s, const DeviceSample& sample,
                               SafetyOutput& output) noexcept {
  const bool is_rotary = limits_.kinematics == Kinematics::kRotary1;
  const double speed = is_rotary ? std::abs(sample.velocity.x()) : safe_norm(sample.velocity);
  if (speed > velocity_trip_) begin_ramp_down(time_s, kEventVelocityTrip, output);
  const double margin = options_.workspace_margin_m;
  bool outside = false;
  for (int axis = 0; axis < (is_rotary ? 1 : 3); ++axis) {
    outside = outside || sample.position[axis] < limits_.workspace_min[axis] + margin ||
              sample.position[axis] > limits_.workspace_max[axis] - margin;
  }
  if (outside) begin_ramp_down(time_s, kEventWorkspaceTrip, output);
}

// The force at the trip, scaled linearly to zero over shutdown_ramp_s: the per-tick change
// is at most force_limit · dt / shutdown_ramp_s, within the rate limit (checked in the
// constructor).
SafetyOutput SafetyLayer::ramp_down(double time_s, SafetyOutput output) noexcept {
  const double elapsed_s = std::max(0.0, time_s - ramp_down_start_s_);
  ramp_down_remaining_ = std::min(ramp_down_remaining_, 1.0 - elapsed_s / options_.shutdown_ramp_s);
  const double remaining = ramp_down_remaining_;
  if (remaining <= 0.0 || ramp_down_from_force_.isZero(0.0)) {
    return stopped_output(output.events | kEventStopped);
  }
  previous_force_ = remaining * ramp_down_from_force_;
  scale_ = remaining * ramp_down_from_scale_;
  output.force = previous_force_;
  output.scale = scale_;
  output.state = state_;
  return output;
}

void SafetyLayer::advance_start_ramp(double time_s, SafetyOutput& output) noexcept {
  const double ramp =
      options_.startup_ramp_s > 0.0 ? (time_s - start_time_s_) / options_.startup_ramp_s : 1.0;
  scale_ = std::clamp(ramp, 0.0, 1.0);
  if (scale_ >= 1.0) {
    state_ = SafetyState::kRunning;
    output.events |= kEventStartRampDone;
  }
}

Vec3 SafetyLayer::limit_force(const Vec3& desired_force, double dt_s, bool& force_clipped,
                              bool& rate_clipped) const noexcept {
  Vec3 target = desired_force;
  if (limits_.kinematics == Kinematics::kRotary1) target.y() = target.z() = 0.0;
  // Limit the magnitude before scaling, so that a huge finite request cannot overflow.
  const double requested = safe_norm(target);
  if (requested > force_limit_) {
    target *= force_limit_ / requested;
    force_clipped = true;
  }
  target *= scale_;
  // After a late tick the force still changes no faster than over max_tick_interval_s: it
  // ramps from what the device held towards the new target over the next ticks.
  const double max_change = force_rate_limit_ * std::min(dt_s, options_.max_tick_interval_s);
  const Vec3 change = target - previous_force_;
  const double change_size = safe_norm(change);
  if (change_size > max_change) {
    target = previous_force_ + change * (max_change / change_size);
    rate_clipped = true;
  }
  return target;
}

// Each clipping episode is reported once, again only after kQuietTicksBeforeReraise ticks
// without clipping.
void SafetyLayer::report_clipping(bool force_clipped, bool rate_clipped,
                                  SafetyOutput& output) noexcept {
  if (force_clipped) {
    clipping_quiet_ticks_ = 0;
    if (!clipping_) output.events |= kEventForceLimited;
    clipping_ = true;
  } else if (clipping_ && ++clipping_quiet_ticks_ >= kQuietTicksBeforeReraise) {
    clipping_ = false;
  }
  if (rate_clipped) {
    rate_quiet_ticks_ = 0;
    if (!rate_clipping_) output.events |= kEventForceRateLimited;
    rate_clipping_ = true;
  } else if (rate_clipping_ && ++rate_quiet_ticks_ >= kQuietTicksBeforeReraise) {
    rate_clipping_ = false;
  }
}

std::string PassivityOptions::validate() const {
  if (!(energy_budget_J >= 0.0) || !std::isfinite(energy_budget_J)) {
    return option_problem("energy_budget_J", energy_budget_J, "must be >= 0");
  }
  if (!(budget_recovery_W >= 0.0) || !std::isfinite(budget_recovery_W)) {
    return option_problem("budget_recovery_W", budget_recovery_W, "must be >= 0");
  }
  if (!positive_finite(max_damping_Nm_s_per_rad)) {
    return option_problem("max_damping_Nm_s_per_rad", max_damping_Nm_s_per_rad, "must be > 0");
  }
  return "";
}

PassivityController::PassivityController(const PassivityOptions& options) : options_(options) {
  if (std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("passivity options: ").append(problem));
  }
}

double PassivityController::step(double active_torque_Nm, double omega_rad_s, double dt_s,
                                 std::uint32_t& events) noexcept {
  if (!options_.enabled) return 0.0;
  if (!std::isfinite(active_torque_Nm) || !std::isfinite(omega_rad_s) || !(dt_s > 0.0) ||
      !std::isfinite(dt_s)) {
    return 0.0;  // the safety layer trips on such inputs; nothing to observe here
  }
  const double injected_J = active_torque_Nm * omega_rad_s * dt_s;
  if (std::isfinite(injected_J)) energy_J_ += injected_J;
  energy_J_ = std::max(0.0, energy_J_ - options_.budget_recovery_W * dt_s);
  const double excess_J = energy_J_ - options_.energy_budget_J;
  double damping = 0.0;
  if (excess_J > 0.0) {
    // Damping b that dissipates the excess in this tick (b ω² dt = excess), within the cap.
    const double omega_squared_dt = omega_rad_s * omega_rad_s * dt_s;
    damping = options_.max_damping_Nm_s_per_rad;
    if (omega_squared_dt > 0.0 && excess_J / omega_squared_dt < damping) {
      damping = excess_J / omega_squared_dt;
    }
    const double dissipated_J = damping * omega_squared_dt;
    energy_J_ -= dissipated_J;
    dissipated_J_ += dissipated_J;
    if (!active_) events |= kEventPassivityActive;
    active_ = true;
  } else {
    active_ = false;
  }
  return -damping * omega_rad_s;
}

double stiffness_bound(double device_inertia, double tick_period_s) noexcept {
  const double factor = 4.0 * kMaxRequiredDampingRatio / 3.0;
  return factor * factor * device_inertia / (tick_period_s * tick_period_s);
}

namespace {

struct SlopePoint {
  double theta_rad;
  double torque_Nm;
  double restoring_Nm_per_rad;  // −∂τ/∂θ
};

class SlopeSearch {
 public:
  explicit SlopeSearch(const DoorModel& model) : model_(model) {}

  SlopePoint evaluate(double theta_rad) {
    const TorqueDerivatives d = model_.torque_derivatives(theta_rad, 0.0);
    ++result.evaluations;
    const SlopePoint point{theta_rad, d.torque_Nm, -d.dtorque_dtheta_Nm_per_rad};
    if (point.restoring_Nm_per_rad > result.slope_Nm_per_rad) {
      result.slope_Nm_per_rad = point.restoring_Nm_per_rad;
      result.theta_rad = theta_rad;
    }
    return point;
  }

  // Bisects while the end slopes disagree or the secant is steeper than both ends (an edge
  // that lies between the two points).
  void refine(const SlopePoint& a, const SlopePoint& b, int depth) {
    if (depth > kMaxDepth || result.evaluations > kMaxEvaluations) return;
    const double width = b.theta_rad - a.theta_rad;
    if (width < 1e-12) return;
    const double secant = -(b.torque_Nm - a.torque_Nm) / width;
    const double scale = std::max(
        {std::abs(a.restoring_Nm_per_rad), std::abs(b.restoring_Nm_per_rad), std::abs(secant)});
    const double tolerance = kRelativeTolerance * scale + kAbsoluteTolerance_Nm_per_rad;
    const bool ends_differ = std::abs(a.restoring_Nm_per_rad - b.restoring_Nm_per_rad) > tolerance;
    const bool secant_differs =
        std::abs(secant - 0.5 * (a.restoring_Nm_per_rad + b.restoring_Nm_per_rad)) > tolerance;
    if (!ends_differ && !secant_differs) return;
    const SlopePoint middle = evaluate(0.5 * (a.theta_rad + b.theta_rad));
    refine(a, middle, depth + 1);
    refine(middle, b, depth + 1);
  }

  RestoringSlope result;

  static constexpr int kGridIntervals = 4096;
  static constexpr int kMaxDepth = 40;
  static constexpr int kMaxEvaluations = 400000;
  static constexpr double kRelativeTolerance = 0.02;
  static constexpr double kAbsoluteTolerance_Nm_per_rad = 1.0;

 private:
  const DoorModel& model_;
};

void check_arguments(double device_inertia, double tick_period_s, double theta_lo_rad,
                     double theta_hi_rad) {
  if (!positive_finite(device_inertia)) {
    throw std::invalid_argument(std::string("check_parameter_set: device_inertia = ")
                                    .append(format_number(device_inertia))
                                    .append(" must be > 0"));
  }
  if (!positive_finite(tick_period_s)) {
    throw std::invalid_argument(std::string("check_parameter_set: tick_period_s = ")
                                    .append(format_number(tick_period_s))
                                    .append(" must be > 0"));
  }
  if (!std::isfinite(theta_lo_rad) || !std::isfinite(theta_hi_rad) ||
      !(theta_lo_rad < theta_hi_rad)) {
    throw std::invalid_argument(std::string("check_parameter_set: the angle range [")
                                    .append(format_number(theta_lo_rad))
                                    .append(", ")
                                    .append(format_number(theta_hi_rad))
                                    .append("] rad must be finite and not empty"));
  }
}

std::string check_values_and_bounds(const DoorModel& model, std::span<const double> values) {
  if (static_cast<int>(values.size()) != model.parameter_count()) {
    return std::string("expected ")
        .append(std::to_string(model.parameter_count()))
        .append(" parameter values, got ")
        .append(std::to_string(values.size()));
  }
  const std::span<const Bounds> bounds = model.parameter_bounds();
  for (int i = 0; i < model.parameter_count(); ++i) {
    const double value = values[static_cast<std::size_t>(i)];
    if (!std::isfinite(value)) {
      return std::string(model.parameter_name(i))
          .append(" = ")
          .append(format_number(value))
          .append(" is not finite");
    }
    const Bounds& b = bounds[static_cast<std::size_t>(i)];
    if (value < b.lower || value > b.upper) {
      return std::string(model.parameter_name(i))
          .append(" = ")
          .append(format_number(value))
          .append(" is outside its bounds [")
          .append(format_number(b.lower))
          .append(", ")
          .append(format_number(b.upper))
          .append("]");
    }
  }
  return "";
}

std::string check_stiffness(const DoorModel& model, const DoorMapping& mapping,
                            double device_inertia, double tick_period_s, double theta_lo_rad,
                            double theta_hi_rad) {
  const RestoringSlope slope = stiffest_restoring_slope(model, theta_lo_rad, theta_hi_rad);
  const double on_device = mapping.stiffness_on_device(slope.slope_Nm_per_rad);
  const double bound = stiffness_bound(device_inertia, tick_period_s);
  if (on_device <= bound) return "";
  const bool rotary = mapping.kinematics() == Kinematics::kRotary1;
  return std::string("the stiffest restoring slope, -dtau/dtheta = ")
      .append(three_digits(slope.slope_Nm_per_rad))
      .append(" N*m/rad at theta = ")
      .append(three_digits(slope.theta_rad))
      .append(" rad, is ")
      .append(three_digits(on_device))
      .append(rotary ? " N*m/rad" : " N/m")
      .append(" on the device, above the stability bound ")
      .append(three_digits(bound))
      .append(rotary ? " N*m/rad" : " N/m")
      .append(" for an inertia of ")
      .append(three_digits(device_inertia))
      .append(rotary ? " kg*m^2" : " kg")
      .append(" at a tick period of ")
      .append(three_digits(tick_period_s))
      .append(" s");
}

}  // namespace

RestoringSlope stiffest_restoring_slope(const DoorModel& model, double theta_lo_rad,
                                        double theta_hi_rad) {
  SlopeSearch search(model);
  const int n = SlopeSearch::kGridIntervals;
  SlopePoint previous = search.evaluate(theta_lo_rad);
  for (int i = 1; i <= n; ++i) {
    const double theta =
        i == n ? theta_hi_rad : theta_lo_rad + (theta_hi_rad - theta_lo_rad) * i / n;
    const SlopePoint next = search.evaluate(theta);
    search.refine(previous, next, 0);
    previous = next;
  }
  return search.result;
}

std::string check_parameter_set(const DoorModel& model, const DoorMapping& mapping,
                                double device_inertia, double tick_period_s, double theta_lo_rad,
                                double theta_hi_rad) {
  check_arguments(device_inertia, tick_period_s, theta_lo_rad, theta_hi_rad);
  if (std::string problem = check_values_and_bounds(model, model.parameter_values());
      !problem.empty()) {
    return problem;
  }
  return check_stiffness(model, mapping, device_inertia, tick_period_s, theta_lo_rad, theta_hi_rad);
}

std::string check_parameter_values(const DoorModel& model, std::span<const double> values,
                                   const DoorMapping& mapping, double device_inertia,
                                   double tick_period_s, double theta_lo_rad, double theta_hi_rad) {
  check_arguments(device_inertia, tick_period_s, theta_lo_rad, theta_hi_rad);
  if (std::string problem = check_values_and_bounds(model, values); !problem.empty()) {
    return problem;
  }
  try {
    const DoorModel candidate =
        model.with_parameter_values(std::vector<double>(values.begin(), values.end()));
    return check_stiffness(candidate, mapping, device_inertia, tick_period_s, theta_lo_rad,
                           theta_hi_rad);
  } catch (const std::invalid_argument& error) {
    return error.what();  // a constraint between parameters (θ0 < θ1, ...) names itself
  }
}

}  // namespace doorbench::haptic
