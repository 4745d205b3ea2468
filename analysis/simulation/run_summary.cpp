#include "analysis/simulation/run_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/units.h"

namespace doorbench {

RunSummary summarize_run(const DoorModel& model, const Trajectory& run) {
  RunSummary summary;
  const double r_h = model.geometry().handle_radius_m;
  int stops_term = -1;
  std::vector<int> friction_terms;
  for (int term = 0; term < model.term_count(); ++term) {
    if (model.term_name(term) == "stops") stops_term = term;
    const std::string& name = model.term_name(term);
    if (name.find("friction") != std::string::npos || name == "viscous_damping" ||
        name == "stribeck") {
      friction_terms.push_back(term);
    }
  }
  std::vector<double> friction_samples_N;
  for (std::size_t i = 0; i < run.size(); ++i) {
    const double theta = run.theta_rad[i];
    const double omega = run.omega_rad_s[i];
    const double stops = stops_term >= 0 ? run.terms_Nm[stops_term][i] : 0.0;
    const double mechanism_N = (run.tau_m_Nm[i] - stops) / r_h;
    if (theta < kLatchZoneRad && theta > 0) {
      if (omega > 0)
        summary.peak_unlatch_force_N = std::max(summary.peak_unlatch_force_N, -mechanism_N);
      if (omega < 0) summary.peak_latch_force_N = std::max(summary.peak_latch_force_N, mechanism_N);
    }
    summary.largest_opening_hand_force_N =
        std::max(summary.largest_opening_hand_force_N, run.force_N[i]);
    summary.largest_closing_hand_force_N =
        std::max(summary.largest_closing_hand_force_N, -run.force_N[i]);
    summary.largest_speed_rad_s = std::max(summary.largest_speed_rad_s, std::abs(omega));
    summary.largest_angle_rad = std::max(summary.largest_angle_rad, theta);
    if (theta > kLatchZoneRad && theta < model.geometry().theta_max_rad - 0.1 &&
        std::abs(omega) > 0.05) {
      double friction_Nm = 0.0;
      for (int term : friction_terms) friction_Nm += run.terms_Nm[term][i];
      friction_samples_N.push_back(std::abs(friction_Nm) / r_h);
    }
  }
  if (!friction_samples_N.empty()) {
    auto middle = friction_samples_N.begin() + friction_samples_N.size() / 2;
    std::nth_element(friction_samples_N.begin(), middle, friction_samples_N.end());
    summary.free_movement_friction_N = *middle;
  }
  if (run.size() > 0) summary.final_angle_rad = run.theta_rad.back();
  return summary;
}

std::string format_summary(const RunSummary& s) {
  char text[512];
  std::snprintf(
      text, sizeof text,
      "  peak force to unlatch      %6.1f N   (hand's largest opening push %.1f N)\n"
      "  peak force to latch        %6.1f N   (hand's largest closing push %.1f N)\n"
      "  friction in free movement  %6.1f N   (median, at the handle)\n"
      "  largest speed              %6.1f deg/s, largest angle %.1f deg, final %.2f deg\n",
      s.peak_unlatch_force_N, s.largest_opening_hand_force_N, s.peak_latch_force_N,
      s.largest_closing_hand_force_N, s.free_movement_friction_N,
      s.largest_speed_rad_s * kDegPerRad, s.largest_angle_rad * kDegPerRad,
      s.final_angle_rad * kDegPerRad);
  return text;
}

}  // namespace doorbench
