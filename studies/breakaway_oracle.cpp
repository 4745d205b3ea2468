// Not a timing: how far the recording family's data can tell breakaway friction apart from
// nothing, whatever the examination does (docs/residual-loop.md, "What the data allow"). For each
// draw of the family test's conditions (fixtures/recording_family.h, breakaway_test_family();
// the draws of tests/analysis/test_residual_loop_family.cpp), the recording with the issue's
// breakaway friction (d_s − d1 = 1.5 N·m, w_s = 0.05 rad/s) and the clean one of the same
// conditions and seed are each fitted twice:
//   base:   the loop's start fit (the sensory reference door, the loop's fit options);
//   oracle: the refit the loop would make if its examination pointed at breakaway friction
//           with the true values: from the base fit with Stribeck friction at d1 + 1.5 N·m,
//           0.05 rad/s, and from the true door; the lower fitted sum of squares is kept
//           (fixtures/breakaway_refit.h).
// Each refit is judged by the loop's acceptance rule (LoopOptions' defaults): held-out window
// RMSE down by more than min_held_out_improvement, BIC down, the amplitude d_s − d1 at least
// min_amplitude_z standard uncertainties from zero, neither of the effect's parameters at a
// bound or undetermined. The breakaway recordings that pass are what an examination pointing
// at the truth would find (not a strict bound: a refit from elsewhere may do better); the
// clean ones that pass are what the same rule would add for nothing. Beside it the loop runs
// as the family test runs it (its first step, no structure check).
//
//   doorbench_breakaway_oracle [--whole-family] DRAW [DRAW ...]
//                                    one CSV line per draw and recording; --whole-family:
//                                    the done-when's family instead (every hand, 50 Hz to
//                                    1 kHz, the same two sensor sets; conditions drawn from
//                                    seed 5000 + DRAW, recordings from 6000 + DRAW)
//   doorbench_breakaway_oracle --no-loop [--whole-family] DRAW ...
//                                    the same without the loop (loop_first "not-run")
//   doorbench_breakaway_oracle --header           the CSV's header line
//   doorbench_breakaway_oracle --known [--whole-family] DRAW [DRAW ...]
//                                    instead, for the breakaway recording of each draw:
//                                    d_s's standard uncertainty at the true door with the
//                                    door's parameters free, with the door known (d_s and w_s
//                                    fitted) and with w_s known too
//                                    (breakaway_amplitude_uncertainty), one line "draw,hand,
//                                    rate_hz,sensors,u_door_free_N_m,u_door_known_N_m,
//                                    u_all_known_N_m"
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "analysis/loop/residual_loop.h"
#include "fixtures/breakaway_refit.h"
#include "fixtures/recording_family.h"
#include "fixtures/reference_doors.h"

using namespace doorbench;

namespace {

constexpr double kExcess_N_m = 1.5;
constexpr double kWidth_rad_s = 0.05;
constexpr std::uint32_t kFirstSeed = 2000;        // the family test's
constexpr std::uint32_t kWholeFamilySeed = 5000;  // --whole-family

struct Verdict {
  testing::BreakawayRefit refit;
  std::string loop_first = "none";  // the loop's first added effect
};

Verdict judge(const PreparedData& data, const LoopOptions& loop, bool run_loop) {
  Verdict v{testing::refit_from_true_breakaway(data, loop, kExcess_N_m, kWidth_rad_s), "none"};
  if (std::getenv("ORACLE_REPORTS") != nullptr) {
    std::fprintf(stderr, "base fit:\n%s\noracle refit:\n%s\n", v.refit.base.full_report().c_str(),
                 v.refit.refit.full_report().c_str());
  }
  if (!run_loop) {
    v.loop_first = "not-run";
    return v;
  }
  LoopOptions first_step = loop;
  first_step.max_steps = 1;
  first_step.structure_check = false;
  const LoopResult found = run_residual_loop(testing::sensory_reference(), data, first_step);
  if (!found.steps.empty()) v.loop_first = found.steps.front().effect_name;
  return v;
}

void print_line(int draw, const testing::RecordingConditions& c, const char* recording,
                const Verdict& v) {
  const testing::BreakawayRefit& r = v.refit;
  std::printf("%d,%s,%g,%s,%s,%.6g,%.6g,%.4f,%.6g,%.6g,%.6g,%.3g,%.6g,%d,%d,%s\n", draw,
              c.hand.c_str(), c.sample_rate_hz, c.sensors.c_str(), recording,
              r.base_figures.held_out_rmse_rad_s, r.refit_figures.held_out_rmse_rad_s,
              r.held_out_fall(), r.refit_figures.bic - r.base_figures.bic, r.amplitude_N_m,
              r.amplitude_u_N_m, r.amplitude_z(), r.width_rad_s, r.bound_or_undetermined ? 1 : 0,
              r.qualifies ? 1 : 0, v.loop_first.c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s DRAW [DRAW ...] | --header\n", argv[0]);
    return 2;
  }
  if (std::strcmp(argv[1], "--header") == 0) {
    std::printf(
        "draw,hand,rate_hz,sensors,recording,base_held_out_rad_s,oracle_held_out_rad_s,"
        "held_out_fall,bic_change,amplitude_N_m,amplitude_u_N_m,amplitude_z,w_s_rad_s,"
        "bound_or_undetermined,qualifies,loop_first\n");
    return 0;
  }
  const LoopOptions loop;
  const bool known = std::strcmp(argv[1], "--known") == 0;
  const bool run_loop = std::strcmp(argv[1], "--no-loop") != 0;
  const int first_arg = known || !run_loop ? 2 : 1;
  const bool whole = argc > first_arg && std::strcmp(argv[first_arg], "--whole-family") == 0;
  testing::FamilyOptions family = testing::breakaway_test_family();
  if (whole) {
    family.hands = testing::FamilyOptions{}.hands;
    family.sample_rates_hz = testing::FamilyOptions{}.sample_rates_hz;
  }
  const std::uint32_t first_seed = whole ? kWholeFamilySeed : kFirstSeed;
  const DoorModel truth = testing::sensory_reference_with_breakaway(kExcess_N_m, kWidth_rad_s);
  for (int i = first_arg + (whole ? 1 : 0); i < argc; ++i) {
    const std::string text = argv[i];
    const bool digits = text.find_first_not_of("0123456789") == std::string::npos;
    if (text.empty() || text.size() > 6 || !digits) {
      std::fprintf(stderr,
                   "doorbench_breakaway_oracle: DRAW must be a whole number from 0, got '%s'\n",
                   argv[i]);
      return 2;
    }
    const int draw = std::stoi(text);
    const testing::RecordingConditions c =
        testing::draw_conditions(first_seed + static_cast<std::uint32_t>(draw), family);
    const std::uint32_t seed = first_seed + 1000 + static_cast<std::uint32_t>(draw);
    if (known) {
      const PreparedData data = testing::family_recording(truth, c, seed);
      std::printf("%d,%s,%g,%s", draw, c.hand.c_str(), c.sample_rate_hz, c.sensors.c_str());
      for (testing::Known what :
           {testing::Known::kDoorFree, testing::Known::kDoorKnown, testing::Known::kAllKnown}) {
        std::printf(",%.6g", testing::breakaway_amplitude_uncertainty(data, loop, what, kExcess_N_m,
                                                                      kWidth_rad_s));
      }
      std::printf("\n");
      std::fflush(stdout);
      continue;
    }
    print_line(draw, c, "breakaway",
               judge(testing::family_recording(truth, c, seed), loop, run_loop));
    print_line(
        draw, c, "clean",
        judge(testing::family_recording(testing::sensory_reference(), c, seed), loop, run_loop));
  }
  return 0;
}
