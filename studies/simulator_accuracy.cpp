// Measures the simulator's error on the reference door's 10 s open-close by the virtual
// hand: the default adaptive solution against solutions with 10x and 1000x tighter
// tolerances, and the fixed-step method against one with a 10x smaller step. Prints a
// Markdown table for docs/simulator.md.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/model/parameter_file.h"
#include "analysis/simulation/virtual_hand.h"

using namespace doorbench;

namespace {

struct Difference {
  double theta_rad = 0.0;
  double omega_rad_s = 0.0;
};

Difference largest_difference(const Trajectory& a, const Trajectory& b) {
  Difference d;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d.theta_rad = std::max(d.theta_rad, std::abs(a.theta_rad[i] - b.theta_rad[i]));
    d.omega_rad_s = std::max(d.omega_rad_s, std::abs(a.omega_rad_s[i] - b.omega_rad_s[i]));
  }
  return d;
}

SimulationOptions tighter(SimulationOptions options, double factor) {
  options.relative_tolerance /= factor;
  options.angle_tolerance_rad /= factor;
  options.rate_tolerance_rad_s /= factor;
  return options;
}

}  // namespace

int main() {
  std::vector<double> times(10001);
  for (std::size_t i = 0; i < times.size(); ++i) times[i] = static_cast<double>(i) * 1e-3;
  std::printf(
      "| model | method | against | max abs theta error (rad) | max abs omega error (rad/s) "
      "| steps (rejected) | smallest step (s) |\n|---|---|---|---|---|---|---|\n");
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel model = reference_model(kind);
    const VirtualHand hand(VirtualHandOptions{}, model.geometry().handle_radius_m);
    const SimulationOptions defaults;
    const Trajectory run = simulate(model, hand, DoorState{}, times, defaults);
    for (double factor : {10.0, 1000.0}) {
      const Trajectory finer = simulate(model, hand, DoorState{}, times, tighter(defaults, factor));
      const Difference d = largest_difference(run, finer);
      std::printf(
          "| %s | adaptive, defaults | tolerances / %g | %.2e | %.2e | %ld (%ld) | %.2e |\n",
          std::string(to_string(kind)).c_str(), factor, d.theta_rad, d.omega_rad_s,
          run.stats.accepted_steps, run.stats.rejected_steps, run.stats.smallest_step_s);
    }
    for (double step_s : {1e-4, 2e-5}) {
      SimulationOptions fixed;
      fixed.method = SimulationOptions::Method::kFixedStep;
      fixed.fixed_step_s = step_s;
      const Trajectory coarse = simulate(model, hand, DoorState{}, times, fixed);
      fixed.fixed_step_s = step_s / 10;
      const Trajectory fine = simulate(model, hand, DoorState{}, times, fixed);
      const Difference d = largest_difference(coarse, fine);
      std::printf("| %s | fixed step %g s | step / 10 | %.2e | %.2e | %ld (0) | %.0e |\n",
                  std::string(to_string(kind)).c_str(), step_s, d.theta_rad, d.omega_rad_s,
                  coarse.stats.accepted_steps, step_s);
    }
  }
  return 0;
}
