#pragma once
// The detailed physical door model of door-models.md §3 and §3.1: a bottom-hinged
// door in side view (x out of the cabinet, y up, hinge at the origin), its gravity,
// balancing spring, frictions, latch cam, seal and end stops.
#include <array>
#include <string>

#include "analysis/model/parameters.h"
#include "analysis/model/sensory_model.h"  // end_stop_torque
#include "analysis/model/switches.h"

namespace doorbench::physical {

inline constexpr double kGravity_m_s2 = 9.80665;

enum Index : int {
  kMassDoor,
  kLc,
  kJd,
  kKs,
  kL0,
  kF0,
  kAx,
  kAy,
  kBu,
  kBv,
  kTh,
  kBh,
  kWf,
  kMuG,
  kRl,
  kKl,
  kFl0,
  kH,
  kAlphaO,
  kAlphaC,
  kMuL,
  kE,
  kKSeal,
  kThetaSeal,
  kKStop,
  kCStop,
  kParameterCount
};

inline constexpr std::array<ParameterInfo, kParameterCount> kParameterInfo = {{
    {"m_d", "kg", "door mass"},
    {"l_c", "m", "hinge to centre of mass along the door"},
    {"J_d", "kg*m^2", "door inertia about the hinge"},
    {"k_s", "N/m", "balancing spring rate"},
    {"L0", "m", "balancing spring free length"},
    {"F0", "N", "balancing spring initial tension"},
    {"A_x", "m", "spring anchor on the cabinet, x"},
    {"A_y", "m", "spring anchor on the cabinet, y"},
    {"B_u", "m", "spring lever point on the door, along the door"},
    {"B_v", "m", "spring lever point on the door, along its outward normal"},
    {"T_h", "N*m", "hinge Coulomb friction"},
    {"b_h", "N*m*s/rad", "hinge viscous friction"},
    {"w_f", "rad/s", "friction smoothing speed"},
    {"mu_g", "m", "spring-guide friction arm"},
    {"r_l", "m", "latch radius"},
    {"k_l", "N/m", "latch catch spring"},
    {"F_l0", "N", "latch catch preload"},
    {"h", "m", "latch catch depth"},
    {"alpha_o", "rad", "latch ramp angle, opening side"},
    {"alpha_c", "rad", "latch ramp angle, closing side"},
    {"mu_l", "1", "latch ramp friction coefficient"},
    {"e", "m", "latch cam smoothing length"},
    {"k_seal", "N*m/rad", "door seal stiffness"},
    {"theta_seal", "rad", "angle where the seal stops touching"},
    {"k_stop", "N*m/rad", "stiffness of the end stops"},
    {"c_stop", "N*m*s/rad", "damping of the end stops"},
}};

enum Term : int {
  kGravityTerm,
  kSpring,
  kHingeFriction,
  kGuideFriction,
  kLatch,
  kSeal,
  kStops,
  kTermCount
};
inline constexpr std::array<std::string_view, kTermCount> kTermNames = {
    "gravity", "spring", "hinge_friction", "guide_friction", "latch", "seal", "stops"};

template <typename T>
struct Parameters {
  T m_d, l_c, J_d, k_s, L0, F0, A_x, A_y, B_u, B_v, T_h, b_h, w_f, mu_g, r_l, k_l, F_l0, h, alpha_o,
      alpha_c, mu_l, e, k_seal, theta_seal, k_stop, c_stop;

  static Parameters from(const T* p) {
    return {p[kMassDoor], p[kLc],    p[kJd],        p[kKs],    p[kL0],     p[kF0],     p[kAx],
            p[kAy],       p[kBu],    p[kBv],        p[kTh],    p[kBh],     p[kWf],     p[kMuG],
            p[kRl],       p[kKl],    p[kFl0],       p[kH],     p[kAlphaO], p[kAlphaC], p[kMuL],
            p[kE],        p[kKSeal], p[kThetaSeal], p[kKStop], p[kCStop]};
  }
};

// Balancing spring: its tension (N) and its torque on the door (N*m) at θ.
template <typename T>
struct SpringState {
  T tension_N;
  T torque_Nm;
};

// θ's sine and cosine are given: the gravity term needs the sine too.
template <typename T>
SpringState<T> balancing_spring(const Parameters<T>& p, const T& sin_theta, const T& cos_theta) {
  using std::sqrt;
  // B(θ) = B_u (sin θ, cos θ) + B_v (cos θ, −sin θ)
  const T b_x = p.B_u * sin_theta + p.B_v * cos_theta;
  const T b_y = p.B_u * cos_theta - p.B_v * sin_theta;
  const T dx = p.A_x - b_x;
  const T dy = p.A_y - b_y;
  const T length = sqrt(dx * dx + dy * dy);
  if (length < p.L0) return {T(0.0), T(0.0)};
  const T tension = p.F0 + p.k_s * (length - p.L0);
  const T force_x = tension * dx / length;
  const T force_y = tension * dy / length;
  // The moment is counter-clockwise positive; opening turns the door clockwise.
  return {tension, -(b_x * force_y - b_y * force_x)};
}

template <typename T>
SpringState<T> balancing_spring(const Parameters<T>& p, const T& theta) {
  using std::cos;
  using std::sin;
  return balancing_spring(p, T(sin(theta)), T(cos(theta)));
}

// The latch cam's corners, which depend on the parameters alone (tan is the costliest
// part of an evaluation): a DoorModel computes them once per parameter set. The same
// expressions as before they were hoisted, so the torque is the same to the bit.
template <typename T>
struct LatchShape {
  T tan_o;  // tan α_o
  T tan_c;  // tan α_c
  T x1;     // travel at the cam's top: h / tan α_o
  T x2;     // travel where the cam ends: x1 + h / tan α_c
};

template <typename T>
LatchShape<T> latch_shape(const Parameters<T>& p) {
  using std::tan;
  const T tan_o = tan(p.alpha_o);
  const T tan_c = tan(p.alpha_c);
  const T x1 = p.h / tan_o;
  return {tan_o, tan_c, x1, x1 + p.h / tan_c};
}

// The latch of §3.1: force along the striker's travel (N, positive = opening).
// `friction_shape` is tanh(ω / w_f), which the hinge and guide frictions share.
template <typename T>
T latch_force_N(const Parameters<T>& p, const LatchShape<T>& shape, const T& theta,
                const T& friction_shape) {
  const T travel = p.r_l * theta;
  const T rising = travel * shape.tan_o;
  const T falling = (shape.x2 - travel) * shape.tan_c;
  const T cam = softmin(rising, falling, p.e);
  const T deflection = softplus(cam, p.e);
  // dy/dx by the chain rule: softplus' = logistic(z/e); softmin's weights are logistics.
  const T weight_rising = logistic((falling - rising) / p.e);
  const T slope =
      logistic(cam / p.e) * (weight_rising * shape.tan_o - (T(1.0) - weight_rising) * shape.tan_c);
  const T gate = window(travel, T(0.0), shape.x2, T(1.0) / p.e);
  const T normal = (p.F_l0 + p.k_l * deflection) * gate;
  const T friction = p.mu_l * friction_shape;
  return -normal * (slope + friction) / (T(1.0) - slope * friction);
}

template <typename T>
T latch_force_N(const Parameters<T>& p, const T& theta, const T& omega) {
  using std::tanh;
  return latch_force_N(p, latch_shape(p), theta, T(tanh(omega / p.w_f)));
}

// τ_m with the latch's shape already computed for these parameter values (DoorModel's
// cache); every transcendental of θ and ω is taken once.
template <typename T>
T evaluate(const T* parameter_values, const LatchShape<T>& shape, double theta_max_rad,
           const T& theta, const T& omega, T* terms) {
  using std::cos;
  using std::sin;
  using std::tanh;
  const Parameters<T> p = Parameters<T>::from(parameter_values);
  const T sin_theta = sin(theta);
  const SpringState<T> spring = balancing_spring(p, sin_theta, T(cos(theta)));
  const T friction_shape = tanh(omega / p.w_f);
  terms[kGravityTerm] = p.m_d * T(kGravity_m_s2) * p.l_c * sin_theta;
  terms[kSpring] = spring.torque_Nm;
  terms[kHingeFriction] = -p.T_h * friction_shape - p.b_h * omega;
  terms[kGuideFriction] = -p.mu_g * spring.tension_N * friction_shape;
  terms[kLatch] = p.r_l * latch_force_N(p, shape, theta, friction_shape);
  terms[kSeal] = theta < p.theta_seal ? p.k_seal * (p.theta_seal - theta) : T(0.0);
  terms[kStops] = sensory::end_stop_torque(theta, omega, p.k_stop, p.c_stop, theta_max_rad);
  T total = terms[0];
  for (int i = 1; i < kTermCount; ++i) total += terms[i];
  return total;
}

template <typename T>
T evaluate(const T* parameter_values, double theta_max_rad, const T& theta, const T& omega,
           T* terms) {
  return evaluate(parameter_values, latch_shape(Parameters<T>::from(parameter_values)),
                  theta_max_rad, theta, omega, terms);
}

std::string validate(const std::array<double, kParameterCount>& values,
                     const DoorGeometry& geometry);

}  // namespace doorbench::physical
