#include "analysis/simulation/trajectory_io.h"

#include <stdexcept>

namespace doorbench {

Recording to_recording(const Trajectory& run, const std::string& source_description) {
  Recording recording;
  recording.handle_radius_m = run.handle_radius_m;
  if (run.size() >= 2) {
    const double span_s = run.time_s.back() - run.time_s.front();
    recording.sample_rate_hz = static_cast<double>(run.size() - 1) / span_s;
  }
  recording.metadata.emplace_back("source", source_description);
  recording.time_s = run.time_s;
  recording.force_N = run.force_N;
  recording.angle_rad = run.theta_rad;
  recording.rate_rad_s = run.omega_rad_s;
  if (!run.stroke.empty()) recording.stroke = run.stroke;
  recording.extra_names = {"tau_u_Nm", "tau_Nm"};
  recording.extra_columns = {run.tau_u_Nm, run.tau_m_Nm};
  for (std::size_t term = 0; term < run.term_names.size(); ++term) {
    recording.extra_names.push_back("tau_" + run.term_names[term] + "_Nm");
    recording.extra_columns.push_back(run.terms_Nm[term]);
  }
  return recording;
}

RecordedForce recorded_force(const Recording& recording) {
  return RecordedForce(recording.time_s, recording.force_N);
}

DoorState initial_state(const Recording& recording) {
  if (recording.size() == 0) throw std::invalid_argument(recording.source + ": no samples");
  DoorState state;
  state.time_s = recording.time_s.front();
  if (recording.angle_rad) state.theta_rad = recording.angle_rad->front();
  if (recording.rate_rad_s) {
    state.omega_rad_s = recording.rate_rad_s->front();
  } else if (recording.angle_rad && recording.size() >= 2) {
    state.omega_rad_s = ((*recording.angle_rad)[1] - (*recording.angle_rad)[0]) /
                        (recording.time_s[1] - recording.time_s[0]);
  }
  return state;
}

}  // namespace doorbench
