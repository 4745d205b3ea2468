// Not a timing: how far the recording family's data can tell breakaway friction apart from
// nothing, whatever the examination does (issue 30; docs/residual-loop.md, "What the data
// allow"). For each draw of the family test's conditions (tests/support/recording_family.h,
// breakaway_test_family(); the draws of tests/analysis/test_residual_loop_family.cpp), the
// recording with the breakaway friction (d_s − d1 = 1.5 N·m, w_s = 0.05 rad/s) and
// the clean one of the same conditions and seed are each fitted twice:
//   base:   the loop's start fit (the sensory reference door, the loop's fit options);
//   oracle: the refit the loop would make if its examination pointed at breakaway friction
//           with the true values: from the base fit with Stribeck friction at d1 + 1.5 N·m,
//           0.05 rad/s, and from the true door; the lower fitted sum of squares is kept.
// and the loop itself runs on it as the family test runs it (its first step, no structure
// check), so that what it finds can be set beside what the data allow.
// Each pair is judged by the loop's acceptance rule (LoopOptions' defaults): held-out window
// RMSE down by more than min_held_out_improvement, BIC down, the amplitude d_s − d1 at least
// min_amplitude_z standard uncertainties from zero, no parameter at a bound or undetermined.
// The breakaway recordings that pass bound what any examination could find; the clean ones
// that pass are what the same rule would add for nothing.
//
//   doorbench_breakaway_oracle [--whole-family] DRAW [DRAW ...]
//                                    one CSV line per draw and recording; --whole-family:
//                                    the done-when's family instead (every hand, 50 Hz to
//                                    1 kHz, the same two sensor sets; conditions drawn from
//                                    seed 5000 + DRAW, recordings from 6000 + DRAW)
//   doorbench_breakaway_oracle --header           the CSV's header line
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"
#include "analysis/model/effects.h"
#include "core/numbers.h"
#include "tests/support/recording_family.h"
#include "tests/support/reference_doors.h"

using namespace doorbench;

namespace {

constexpr double kExcess_N_m = 1.5;
constexpr double kWidth_rad_s = 0.05;
constexpr std::uint32_t kFirstSeed = 2000;        // the family test's
constexpr std::uint32_t kWholeFamilySeed = 5000;  // --whole-family

const FittedParameter* find_parameter(const FitSummary& summary, const std::string& name) {
  for (const FittedParameter& p : summary.parameters) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

DoorModel with_breakaway(const DoorModel& model, double d1_N_m) {
  EffectSetting setting{effects::Kind::kStribeck, {d1_N_m + kExcess_N_m, kWidth_rad_s}, {}};
  for (const effects::EffectParameter& p : effects::info(effects::Kind::kStribeck).parameters) {
    setting.bounds.push_back(p.default_bounds);
  }
  return model.with_effect(std::move(setting));
}

struct Verdict {
  ModelFigures base, oracle;
  double amplitude_N_m = kNaN, amplitude_u_N_m = kNaN, width_rad_s = kNaN;
  bool bound_or_undetermined = false;
  bool qualifies = false;
  std::string loop_first = "none";  // the loop's first added effect
};

Verdict judge(const PreparedData& data, const LoopOptions& loop) {
  const DoorModel reference = testing::sensory_reference();
  const FitResult base = fit_model(reference, data, loop.fit);
  FitOptions refit = loop.fit;
  refit.latch_start_from_data = false;
  const double d1 = find_parameter(base.summary, "d1")->value;
  const FitResult informed = fit_model(with_breakaway(base.model, d1), data, refit);
  const FitResult from_truth =
      fit_model(testing::sensory_reference_with_breakaway(kExcess_N_m, kWidth_rad_s), data, refit);
  const FitResult& oracle = model_figures(informed.summary).sum_of_squares <=
                                    model_figures(from_truth.summary).sum_of_squares
                                ? informed
                                : from_truth;
  Verdict v;
  if (std::getenv("ORACLE_REPORTS") != nullptr) {
    std::fprintf(stderr, "base fit:\n%s\noracle refit:\n%s\n", base.summary.full_report().c_str(),
                 oracle.summary.full_report().c_str());
  }
  v.base = model_figures(base.summary);
  v.oracle = model_figures(oracle.summary);
  const FittedParameter* d_s = find_parameter(oracle.summary, "stribeck.d_s");
  const FittedParameter* w_s = find_parameter(oracle.summary, "stribeck.w_s");
  const FittedParameter* d1_refit = find_parameter(oracle.summary, "d1");
  v.amplitude_N_m = d_s->value - d1_refit->value;
  v.amplitude_u_N_m = d_s->uncertainty;
  v.width_rad_s = w_s->value;
  for (const FittedParameter& p : oracle.summary.parameters) {
    if (p.free && (p.at_bound || !p.determined)) v.bound_or_undetermined = true;
  }
  const double held_out_fall =
      (v.base.held_out_rmse_rad_s - v.oracle.held_out_rmse_rad_s) / v.base.held_out_rmse_rad_s;
  const double z = std::abs(v.amplitude_N_m) / v.amplitude_u_N_m;
  v.qualifies = held_out_fall > loop.min_held_out_improvement &&
                v.oracle.bic - v.base.bic < -loop.min_bic_decrease && z >= loop.min_amplitude_z &&
                !v.bound_or_undetermined;
  LoopOptions first_step = loop;
  first_step.max_steps = 1;
  first_step.structure_check = false;
  const LoopResult found = run_residual_loop(reference, data, first_step);
  if (!found.steps.empty()) v.loop_first = found.steps.front().effect_name;
  return v;
}

void print_line(int draw, const testing::RecordingConditions& c, const char* recording,
                const Verdict& v) {
  const double fall =
      (v.base.held_out_rmse_rad_s - v.oracle.held_out_rmse_rad_s) / v.base.held_out_rmse_rad_s;
  std::printf("%d,%s,%g,%s,%s,%.6g,%.6g,%.4f,%.6g,%.6g,%.6g,%.3g,%.6g,%d,%d,%s\n", draw,
              c.hand.c_str(), c.sample_rate_hz, c.sensors.c_str(), recording,
              v.base.held_out_rmse_rad_s, v.oracle.held_out_rmse_rad_s, fall,
              v.oracle.bic - v.base.bic, v.amplitude_N_m, v.amplitude_u_N_m,
              std::abs(v.amplitude_N_m) / v.amplitude_u_N_m, v.width_rad_s,
              v.bound_or_undetermined ? 1 : 0, v.qualifies ? 1 : 0, v.loop_first.c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s DRAW [DRAW ...] | --header\n", argv[0]);
    return 2;
  }
  if (std::strcmp(argv[1], "--header") == 0) {
    std::printf("draw,hand,rate_hz,sensors,recording,base_held_out_rad_s,oracle_held_out_rad_s,"
                "held_out_fall,bic_change,amplitude_N_m,amplitude_u_N_m,amplitude_z,w_s_rad_s,"
                "bound_or_undetermined,qualifies,loop_first\n");
    return 0;
  }
  const LoopOptions loop;
  const bool whole = std::strcmp(argv[1], "--whole-family") == 0;
  testing::FamilyOptions family = testing::breakaway_test_family();
  if (whole) {
    family.hands = testing::FamilyOptions{}.hands;
    family.sample_rates_hz = testing::FamilyOptions{}.sample_rates_hz;
  }
  const std::uint32_t first_seed = whole ? kWholeFamilySeed : kFirstSeed;
  for (int i = whole ? 2 : 1; i < argc; ++i) {
    const int draw = std::stoi(argv[i]);
    const testing::RecordingConditions c =
        testing::draw_conditions(first_seed + static_cast<std::uint32_t>(draw), family);
    const std::uint32_t seed = first_seed + 1000 + static_cast<std::uint32_t>(draw);
    const DoorModel truth = testing::sensory_reference_with_breakaway(kExcess_N_m, kWidth_rad_s);
    print_line(draw, c, "breakaway", judge(testing::family_recording(truth, c, seed), loop));
    print_line(draw, c, "clean",
               judge(testing::family_recording(testing::sensory_reference(), c, seed), loop));
  }
  return 0;
}
