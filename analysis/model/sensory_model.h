#pragma once
// The simplified "sensory" door model of door-models.md §2: four phases (unlatching,
// snap, latching, free movement) and the end stops, summed.
#include <array>
#include <string>

#include "analysis/model/parameters.h"
#include "analysis/model/switches.h"

namespace doorbench::sensory {

// Parameter order is the spec's: files and reports list them this way.
enum Index : int {
  kJ,
  kK,
  kKInf,
  kKLock,
  kTheta0,
  kTheta1,
  kTheta2,
  kTheta3,
  kC,
  kD1,
  kD2,
  kS,
  kTheta4,
  kBeta,
  kBetaF,
  kKStop,
  kCStop,
  kParameterCount
};

inline constexpr std::array<ParameterInfo, kParameterCount> kParameterInfo = {{
    {"J", "kg*m^2", "inertia (heaviness)"},
    {"k", "N*m/rad", "soft stiffness near closed (0 < theta < theta0)"},
    {"k_inf", "N*m/rad", "stiff latch spring (theta0 < theta < theta1)"},
    {"k_lock", "N*m/rad", "latching-side stiffness (theta2 < theta < theta3)"},
    {"theta0", "rad", "latch becomes stiff"},
    {"theta1", "rad", "latch releases"},
    {"theta2", "rad", "end of the snap zone"},
    {"theta3", "rad", "end of the latching zone"},
    {"c", "N*m*s/rad", "negative damping in the snap zone"},
    {"d1", "N*m", "dry friction when open"},
    {"d2", "N*m", "friction reduction near closed"},
    {"s", "s/rad", "speed sensitivity of the dry friction"},
    {"theta4", "rad", "where the friction changes"},
    {"beta", "1/rad", "sharpness of the latch switches"},
    {"beta_f", "1/rad", "sharpness of the friction change"},
    {"k_stop", "N*m/rad", "stiffness of the end stops"},
    {"c_stop", "N*m*s/rad", "damping of the end stops"},
}};

enum Term : int { kUnlatch, kSnap, kLatch, kFriction, kStops, kTermCount };
inline constexpr std::array<std::string_view, kTermCount> kTermNames = {"unlatch", "snap", "latch",
                                                                        "friction", "stops"};

// Named view of a parameter array; T is double or a Ceres Jet.
template <typename T>
struct Parameters {
  T J, k, k_inf, k_lock, theta0, theta1, theta2, theta3, c, d1, d2, s, theta4, beta, beta_f, k_stop,
      c_stop;

  static Parameters from(const T* p) {
    return {p[kJ],      p[kK],      p[kKInf],  p[kKLock], p[kTheta0], p[kTheta1],
            p[kTheta2], p[kTheta3], p[kC],     p[kD1],    p[kD2],     p[kS],
            p[kTheta4], p[kBeta],   p[kBetaF], p[kKStop], p[kCStop]};
  }
};

// The end stops (shared with the physical model): the cabinet at θ = 0, the fully
// open door at θ_max.
template <typename T>
T end_stop_torque(const T& theta, const T& omega, const T& k_stop, const T& c_stop,
                  double theta_max_rad) {
  const T theta_max(theta_max_rad);
  if (theta > theta_max) return -(k_stop * (theta - theta_max) + c_stop * omega);
  if (theta < T(0.0)) return -(k_stop * theta + c_stop * omega);
  return T(0.0);
}

// Each term's torque on the door (N*m, positive = opening) at (θ, ω); writes
// kTermCount values to `terms` and returns their sum τ_m.
template <typename T>
T evaluate(const T* parameter_values, double theta_max_rad, const T& theta, const T& omega,
           T* terms) {
  using std::tanh;
  const Parameters<T> p = Parameters<T>::from(parameter_values);
  // Each threshold's switch once: the terms share them.
  const SwitchValues<T> at_theta0 = switch_values(theta, p.theta0, p.beta);
  const SwitchValues<T> at_theta1 = switch_values(theta, p.theta1, p.beta);
  const SwitchValues<T> at_theta2 = switch_values(theta, p.theta2, p.beta);
  const SwitchValues<T> at_theta3 = switch_values(theta, p.theta3, p.beta);
  terms[kUnlatch] = -(p.k * theta + p.k_inf * (theta - p.theta0) * at_theta0.on) * at_theta1.off;
  terms[kSnap] = p.c * omega * window(theta, p.theta1, p.theta2, at_theta1, at_theta2);
  terms[kLatch] =
      p.k_lock * (p.theta3 - theta) * window(theta, p.theta2, p.theta3, at_theta2, at_theta3);
  terms[kFriction] = -tanh(p.s * omega) * (p.d1 - p.d2 * switch_off(theta, p.theta4, p.beta_f));
  terms[kStops] = end_stop_torque(theta, omega, p.k_stop, p.c_stop, theta_max_rad);
  return terms[kUnlatch] + terms[kSnap] + terms[kLatch] + terms[kFriction] + terms[kStops];
}

// Checks every constraint of the spec's parameter table. Empty when all hold, else a
// one-line message naming the parameter and the constraint it breaks.
std::string validate(const std::array<double, kParameterCount>& values,
                     const DoorGeometry& geometry);

// The spec's approximate peak handle forces (N).
double peak_unlatch_force_N(const std::array<double, kParameterCount>& values,
                            const DoorGeometry& geometry);
double peak_latch_force_N(const std::array<double, kParameterCount>& values,
                          const DoorGeometry& geometry);

}  // namespace doorbench::sensory
