#include "analysis/model/sensory_model.h"

#include "analysis/model/constraint_check.h"
#include "core/number_format.h"

namespace doorbench::sensory {

std::string validate(const std::array<double, kParameterCount>& values,
                     const DoorGeometry& geometry) {
  if (std::string message = validate_geometry(geometry); !message.empty()) return message;
  ConstraintCheck check("sensory");
  for (int i = 0; i < kParameterCount; ++i) check.finite(kParameterInfo[i].name, values[i]);
  const Parameters<double> p = Parameters<double>::from(values.data());
  const std::string theta_max = "theta_max = " + format_number(geometry.theta_max_rad);
  check.require(p.J > 0, "J", p.J, "J > 0");
  check.require(p.k >= 0, "k", p.k, "k >= 0");
  check.require(p.k_inf >= 0, "k_inf", p.k_inf, "k_inf >= 0");
  check.require(p.k_lock >= 0, "k_lock", p.k_lock, "k_lock >= 0");
  check.require(p.theta0 > 0, "theta0", p.theta0, "0 < theta0 < theta1");
  check.require(p.theta0 < p.theta1, "theta0", p.theta0, "0 < theta0 < theta1",
                "theta1 = " + format_number(p.theta1));
  check.require(p.theta1 < p.theta2, "theta1", p.theta1, "theta1 < theta2",
                "theta2 = " + format_number(p.theta2));
  check.require(p.theta2 < p.theta3, "theta2", p.theta2, "theta2 < theta3",
                "theta3 = " + format_number(p.theta3));
  check.require(p.theta3 < geometry.theta_max_rad, "theta3", p.theta3, "theta3 < theta_max",
                theta_max);
  check.require(p.c >= 0, "c", p.c, "c >= 0");
  check.require(p.d2 >= 0, "d2", p.d2, "d1 >= d2 >= 0");
  check.require(p.d1 >= p.d2, "d1", p.d1, "d1 >= d2 >= 0", "d2 = " + format_number(p.d2));
  check.require(p.s > 0, "s", p.s, "s > 0");
  check.require(p.theta4 > 0, "theta4", p.theta4, "0 < theta4 < theta_max");
  check.require(p.theta4 < geometry.theta_max_rad, "theta4", p.theta4, "0 < theta4 < theta_max",
                theta_max);
  check.require(p.beta > 0, "beta", p.beta, "beta > 0");
  check.require(p.beta_f > 0, "beta_f", p.beta_f, "beta_f > 0");
  check.require(p.k_stop > 0, "k_stop", p.k_stop, "k_stop > 0");
  check.require(p.c_stop >= 0, "c_stop", p.c_stop, "c_stop >= 0");
  return check.message();
}

double peak_unlatch_force_N(const std::array<double, kParameterCount>& values,
                            const DoorGeometry& geometry) {
  const Parameters<double> p = Parameters<double>::from(values.data());
  return (p.k * p.theta1 + p.k_inf * (p.theta1 - p.theta0)) / geometry.handle_radius_m;
}

double peak_latch_force_N(const std::array<double, kParameterCount>& values,
                          const DoorGeometry& geometry) {
  const Parameters<double> p = Parameters<double>::from(values.data());
  return p.k_lock * (p.theta3 - p.theta2) / geometry.handle_radius_m;
}

}  // namespace doorbench::sensory
