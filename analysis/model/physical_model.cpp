#include "analysis/model/physical_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "analysis/model/constraint_check.h"
#include "core/number_format.h"

namespace doorbench::physical {

// The spec's table gives no constraint column for the physical model beyond the
// self-locking cam; these are the ones its formulas need to mean anything (masses,
// lengths and rates positive, frictions and preloads not negative, ramps below 90°).
std::string validate(const std::array<double, kParameterCount>& values,
                     const DoorGeometry& geometry) {
  if (std::string message = validate_geometry(geometry); !message.empty()) return message;
  ConstraintCheck check("physical");
  for (int i = 0; i < kParameterCount; ++i) check.finite(kParameterInfo[i].name, values[i]);
  const Parameters<double> p = Parameters<double>::from(values.data());
  check.require(p.m_d > 0, "m_d", p.m_d, "m_d > 0");
  check.require(p.l_c > 0, "l_c", p.l_c, "l_c > 0");
  check.require(p.J_d > 0, "J_d", p.J_d, "J_d > 0");
  check.require(p.k_s >= 0, "k_s", p.k_s, "k_s >= 0");
  check.require(p.L0 > 0, "L0", p.L0, "L0 > 0");
  check.require(p.F0 >= 0, "F0", p.F0, "F0 >= 0");
  check.require(p.T_h >= 0, "T_h", p.T_h, "T_h >= 0");
  check.require(p.b_h >= 0, "b_h", p.b_h, "b_h >= 0");
  check.require(p.w_f > 0, "w_f", p.w_f, "w_f > 0");
  check.require(p.mu_g >= 0, "mu_g", p.mu_g, "mu_g >= 0");
  check.require(p.r_l > 0, "r_l", p.r_l, "r_l > 0");
  check.require(p.k_l >= 0, "k_l", p.k_l, "k_l >= 0");
  check.require(p.F_l0 >= 0, "F_l0", p.F_l0, "F_l0 >= 0");
  check.require(p.h > 0, "h", p.h, "h > 0");
  constexpr double kRightAngle = std::numbers::pi / 2;
  check.require(p.alpha_o > 0 && p.alpha_o < kRightAngle, "alpha_o", p.alpha_o,
                "0 < alpha_o < pi/2");
  check.require(p.alpha_c > 0 && p.alpha_c < kRightAngle, "alpha_c", p.alpha_c,
                "0 < alpha_c < pi/2");
  check.require(p.mu_l >= 0, "mu_l", p.mu_l, "mu_l >= 0");
  if (check.ok()) {
    const double steepest = std::tan(std::max(p.alpha_o, p.alpha_c));
    check.require(p.mu_l * steepest < 0.9, "mu_l", p.mu_l,
                  "mu_l * tan(max(alpha_o, alpha_c)) < 0.9 (a self-locking cam)",
                  "mu_l * tan(max(alpha_o, alpha_c)) = " + format_number(p.mu_l * steepest));
  }
  check.require(p.e > 0, "e", p.e, "e > 0");
  check.require(p.k_seal >= 0, "k_seal", p.k_seal, "k_seal >= 0");
  check.require(p.theta_seal >= 0, "theta_seal", p.theta_seal, "theta_seal >= 0");
  check.require(p.k_stop > 0, "k_stop", p.k_stop, "k_stop > 0");
  check.require(p.c_stop >= 0, "c_stop", p.c_stop, "c_stop >= 0");
  return check.message();
}

}  // namespace doorbench::physical
