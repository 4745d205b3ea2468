#include "analysis/simulation/simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/number_format.h"

namespace doorbench {

RecordedForce::RecordedForce(std::vector<double> time_s, std::vector<double> force_N)
    : time_s_(std::move(time_s)), force_N_(std::move(force_N)) {
  if (time_s_.empty() || time_s_.size() != force_N_.size()) {
    throw std::invalid_argument("recorded force needs as many forces as times, and at least one");
  }
  for (std::size_t i = 1; i < time_s_.size(); ++i) {
    if (!(time_s_[i] > time_s_[i - 1])) {
      throw std::invalid_argument("recorded force: time " + format_number(time_s_[i]) +
                                  " s is not after " + format_number(time_s_[i - 1]) + " s");
    }
  }
}

double RecordedForce::force_N(double time_s, double, double) const {
  if (time_s <= time_s_.front()) return force_N_.front();
  if (time_s >= time_s_.back()) return force_N_.back();
  const auto after = std::upper_bound(time_s_.begin(), time_s_.end(), time_s);
  const std::size_t i = static_cast<std::size_t>(after - time_s_.begin());
  const double fraction = (time_s - time_s_[i - 1]) / (time_s_[i] - time_s_[i - 1]);
  return force_N_[i - 1] + fraction * (force_N_[i] - force_N_[i - 1]);
}

std::string SimulationOptions::validate() const {
  auto positive = [](double value) { return std::isfinite(value) && value > 0; };
  if (!positive(relative_tolerance)) return "simulation option relative_tolerance must be > 0";
  if (!positive(angle_tolerance_rad)) return "simulation option angle_tolerance_rad must be > 0";
  if (!positive(rate_tolerance_rad_s)) return "simulation option rate_tolerance_rad_s must be > 0";
  if (!positive(max_step_s)) return "simulation option max_step_s must be > 0";
  if (!positive(min_step_s) || min_step_s > max_step_s) {
    return "simulation option min_step_s must be > 0 and at most max_step_s";
  }
  if (!positive(fixed_step_s)) return "simulation option fixed_step_s must be > 0";
  if (!positive(max_steps_per_s)) return "simulation option max_steps_per_s must be > 0";
  return "";
}

namespace {

// Dormand–Prince 5(4) tableau (Dormand & Prince 1980).
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                 a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
// 5th-order weights (also the last stage's coefficients: first same as last).
constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784,
                 b6 = 11.0 / 84;
// Difference between the 5th- and 4th-order weights: the local error estimate.
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                 e6 = 22.0 / 525, e7 = -1.0 / 40;

}  // namespace

DoorStepper::DoorStepper(const DoorModel& model, const SimulationOptions& options)
    : model_(model),
      options_(options),
      inertia_kg_m2_(model.inertia_kg_m2()),
      next_step_s_(options.method == SimulationOptions::Method::kFixedStep ? options.fixed_step_s
                                                                           : options.max_step_s) {
  if (std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
}

DoorStepper::Derivative DoorStepper::derivative(double time_s, double theta, double omega,
                                                const UserForce& hand) {
  ++stats_.torque_evaluations;
  const double user_torque = model_.geometry().handle_radius_m * hand.force_N(time_s, theta, omega);
  const double mechanism_torque = model_.torque_Nm(theta, omega);
  return {omega, (user_torque + mechanism_torque) / inertia_kg_m2_, user_torque * omega};
}

double DoorStepper::try_step(const DoorState& s, const Derivative& k1, double h,
                             const UserForce& hand, DoorState& candidate, Derivative& k7) {
  const double t = s.time_s;
  auto stage = [&](double c, double dtheta, double domega) {
    return derivative(t + c * h, s.theta_rad + h * dtheta, s.omega_rad_s + h * domega, hand);
  };
  const Derivative k2 = stage(c2, a21 * k1.theta, a21 * k1.omega);
  const Derivative k3 = stage(c3, a31 * k1.theta + a32 * k2.theta, a31 * k1.omega + a32 * k2.omega);
  const Derivative k4 = stage(c4, a41 * k1.theta + a42 * k2.theta + a43 * k3.theta,
                              a41 * k1.omega + a42 * k2.omega + a43 * k3.omega);
  const Derivative k5 = stage(c5, a51 * k1.theta + a52 * k2.theta + a53 * k3.theta + a54 * k4.theta,
                              a51 * k1.omega + a52 * k2.omega + a53 * k3.omega + a54 * k4.omega);
  const Derivative k6 =
      stage(1.0, a61 * k1.theta + a62 * k2.theta + a63 * k3.theta + a64 * k4.theta + a65 * k5.theta,
            a61 * k1.omega + a62 * k2.omega + a63 * k3.omega + a64 * k4.omega + a65 * k5.omega);
  auto combine = [&](double Derivative::*field) {
    return b1 * k1.*field + b3 * k3.*field + b4 * k4.*field + b5 * k5.*field + b6 * k6.*field;
  };
  candidate.time_s = t + h;
  candidate.theta_rad = s.theta_rad + h * combine(&Derivative::theta);
  candidate.omega_rad_s = s.omega_rad_s + h * combine(&Derivative::omega);
  candidate.user_work_J = s.user_work_J + h * combine(&Derivative::work);
  k7 = derivative(candidate.time_s, candidate.theta_rad, candidate.omega_rad_s, hand);

  auto error = [&](double Derivative::*field) {
    return h * (e1 * k1.*field + e3 * k3.*field + e4 * k4.*field + e5 * k5.*field + e6 * k6.*field +
                e7 * k7.*field);
  };
  const double theta_scale =
      options_.angle_tolerance_rad +
      options_.relative_tolerance * std::max(std::abs(s.theta_rad), std::abs(candidate.theta_rad));
  const double omega_scale = options_.rate_tolerance_rad_s +
                             options_.relative_tolerance *
                                 std::max(std::abs(s.omega_rad_s), std::abs(candidate.omega_rad_s));
  return std::max(std::abs(error(&Derivative::theta)) / theta_scale,
                  std::abs(error(&Derivative::omega)) / omega_scale);
}

namespace {
// Four significant digits: for messages about where and why a run stopped.
std::string brief(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}
}  // namespace

std::string stiffness_diagnosis(const DoorModel& model, double theta_rad, double omega_rad_s) {
  const int terms = model.term_count();
  std::vector<double> base(static_cast<std::size_t>(terms)), moved(base.size());
  model.torque_Nm(theta_rad, omega_rad_s, base);
  // The rate of each term's linearized dynamics: |∂τ/∂ω| / J and √(|∂τ/∂θ| / J), 1/s.
  const double inertia = model.inertia_kg_m2();
  const double d_omega = 1e-6 * std::max(1.0, std::abs(omega_rad_s));
  const double d_theta = 1e-7;
  std::vector<double> rate(base.size(), 0.0);
  model.torque_Nm(theta_rad, omega_rad_s + d_omega, moved);
  for (std::size_t t = 0; t < base.size(); ++t) {
    rate[t] = std::abs(moved[t] - base[t]) / d_omega / inertia;
  }
  model.torque_Nm(theta_rad + d_theta, omega_rad_s, moved);
  for (std::size_t t = 0; t < base.size(); ++t) {
    rate[t] = std::max(rate[t], std::sqrt(std::abs(moved[t] - base[t]) / d_theta / inertia));
  }
  std::string text;
  if (!rate.empty()) {
    const auto stiffest =
        static_cast<int>(std::max_element(rate.begin(), rate.end()) - rate.begin());
    const double rate_t = rate[static_cast<std::size_t>(stiffest)];
    text = "the stiffest term is " + model.term_name(stiffest) + " (time constant " +
           (rate_t > 0 && std::isfinite(rate_t) ? brief(1.0 / rate_t) + " s" : "unknown") + ")";
  }
  std::string outside;
  const auto values = model.parameter_values();
  const auto bounds = model.parameter_bounds();
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (values[i] >= bounds[i].lower && values[i] <= bounds[i].upper) continue;
    outside += (outside.empty() ? "" : ", ") + model.parameter_name(static_cast<int>(i)) + " = " +
               format_number(values[i]) + " (bounds " + format_number(bounds[i].lower) + " to " +
               format_number(bounds[i].upper) + ")";
  }
  if (!outside.empty()) text += "; parameters outside their bounds: " + outside;
  return text;
}

void DoorStepper::advance(DoorState& state, double end_time_s, const UserForce& hand) {
  const bool fixed = options_.method == SimulationOptions::Method::kFixedStep;
  if (!started_) {
    started_ = true;
    first_time_s_ = state.time_s;
  }
  while (state.time_s < end_time_s) {
    if (!fixed) {
      const double budget = options_.max_steps_per_s * std::max(1.0, state.time_s - first_time_s_);
      if (static_cast<double>(stats_.accepted_steps + stats_.rejected_steps) > budget) {
        throw std::runtime_error(
            "simulation stopped at t = " + brief(state.time_s) +
            " s, theta = " + brief(state.theta_rad) + " rad after " +
            std::to_string(stats_.accepted_steps + stats_.rejected_steps) +
            " steps (more than max_steps_per_s = " + brief(options_.max_steps_per_s) +
            " per second of door): the equation is too stiff; " +
            stiffness_diagnosis(model_, state.theta_rad, state.omega_rad_s));
      }
    }
    const bool same_start =
        have_derivative_ && k1_hand_ == &hand && k1_state_.time_s == state.time_s &&
        k1_state_.theta_rad == state.theta_rad && k1_state_.omega_rad_s == state.omega_rad_s;
    if (!same_start) {
      k1_ = derivative(state.time_s, state.theta_rad, state.omega_rad_s, hand);
      have_derivative_ = true;
    }
    const double remaining = end_time_s - state.time_s;
    double step = fixed ? options_.fixed_step_s : std::min(next_step_s_, options_.max_step_s);
    // Land exactly on the end time without leaving a sliver of a step behind, and never
    // take a step longer than the controlled one.
    const bool last = step >= remaining * (1 - 1e-12);
    if (last)
      step = remaining;
    else if (remaining < 2 * step)
      step = 0.5 * remaining;

    DoorState candidate;
    Derivative k7;
    const double error_norm = try_step(state, k1_, step, hand, candidate, k7);
    if (fixed && (!std::isfinite(candidate.theta_rad) || !std::isfinite(candidate.omega_rad_s))) {
      throw std::runtime_error("simulation diverged at t = " + format_number(state.time_s) +
                               " s: reduce the fixed step");
    }
    if (fixed || (error_norm <= 1.0 && std::isfinite(error_norm))) {
      state = last ? DoorState{end_time_s, candidate.theta_rad, candidate.omega_rad_s,
                               candidate.user_work_J}
                   : candidate;
      k1_ = k7;
      k1_state_ = state;
      k1_hand_ = &hand;
      ++stats_.accepted_steps;
      if (stats_.accepted_steps == 1 || step < stats_.smallest_step_s)
        stats_.smallest_step_s = step;
      stats_.largest_step_s = std::max(stats_.largest_step_s, step);
      if (!fixed) {
        const double growth =
            error_norm > 0 ? std::clamp(0.9 * std::pow(error_norm, -0.2), 0.2, 5.0) : 5.0;
        // A step cut short to land on the end time says little about the next one.
        next_step_s_ = last ? std::max(next_step_s_, step * growth) : step * growth;
        next_step_s_ = std::min(next_step_s_, options_.max_step_s);
      }
      continue;
    }
    ++stats_.rejected_steps;
    const double shrink =
        std::isfinite(error_norm) ? std::clamp(0.9 * std::pow(error_norm, -0.2), 0.1, 0.9) : 0.1;
    next_step_s_ = step * shrink;
    if (next_step_s_ < options_.min_step_s) {
      throw std::runtime_error("simulation needs a step below " +
                               format_number(options_.min_step_s) +
                               " s at t = " + format_number(state.time_s) +
                               " s, theta = " + format_number(state.theta_rad) + " rad; " +
                               stiffness_diagnosis(model_, state.theta_rad, state.omega_rad_s));
    }
  }
}

Trajectory simulate(const DoorModel& model, const UserForce& hand, const DoorState& initial,
                    std::span<const double> output_times_s, const SimulationOptions& options) {
  if (output_times_s.empty()) throw std::invalid_argument("simulate: no output times");
  if (output_times_s.front() != initial.time_s) {
    throw std::invalid_argument("simulate: the first output time must be the initial state's");
  }
  for (std::size_t i = 1; i < output_times_s.size(); ++i) {
    if (!(output_times_s[i] > output_times_s[i - 1])) {
      throw std::invalid_argument("simulate: output time " + format_number(output_times_s[i]) +
                                  " s is not after " + format_number(output_times_s[i - 1]) + " s");
    }
  }
  const std::size_t count = output_times_s.size();
  Trajectory out;
  out.handle_radius_m = model.geometry().handle_radius_m;
  for (auto* column : {&out.time_s, &out.theta_rad, &out.omega_rad_s, &out.force_N, &out.tau_u_Nm,
                       &out.tau_m_Nm}) {
    column->resize(count);
  }
  for (int i = 0; i < model.term_count(); ++i) out.term_names.push_back(model.term_name(i));
  out.terms_Nm.assign(model.term_count(), std::vector<double>(count));

  DoorStepper stepper(model, options);
  DoorState state = initial;
  std::array<double, DoorModel::kMaxTerms> terms;
  for (std::size_t i = 0; i < count; ++i) {
    stepper.advance(state, output_times_s[i], hand);
    const double force = hand.force_N(state.time_s, state.theta_rad, state.omega_rad_s);
    out.time_s[i] = state.time_s;
    out.theta_rad[i] = state.theta_rad;
    out.omega_rad_s[i] = state.omega_rad_s;
    out.force_N[i] = force;
    out.tau_u_Nm[i] = out.handle_radius_m * force;
    out.tau_m_Nm[i] = model.torque_Nm(state.theta_rad, state.omega_rad_s, terms);
    for (int term = 0; term < model.term_count(); ++term) out.terms_Nm[term][i] = terms[term];
  }
  out.user_work_J = state.user_work_J;
  out.stats = stepper.stats();
  return out;
}

}  // namespace doorbench
