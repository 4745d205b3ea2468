// Not a timing: runs the residual loop on one recording made by the tremor hand
// (fixtures/tremor_recording.h) or on the demo's bench recording, and prints the progress
// lines (each fit with its time), the examination's ranking and the full report, for
// docs/residual-loop.md and docs/PERFORMANCE.md.
//
//   doorbench_loop_study CASE [SEED] [--exam]
//   CASE: clean | stribeck | stribeck-small | stribeck-large | physical | demo | plain-end-stop |
//         soft-close | end-stop | inertia (J held fixed) | viscous | gravity | offset | direction
//   --exam: the examination of the true-model-less fit only (no refits)
//   --serial: refits one after another; --no-second-look: screen_steps = 0
//   --tremor-mm A, --drift-N F: the tremor hand's amplitudes (defaults 0.5 mm, 1 N)
//   --min-z Z: LoopOptions::min_score_z; --only EFFECT: the one candidate (catalogue name);
//   --screen-steps N: LoopOptions::screen_steps; --substeps N: fit.substeps_per_sample
//   --compare-exam: after the loop, the examination's sum of squares at the start fit and
//     at the final model
//   --strokes: each stroke's angle range and its speed through a few angles, then stop
//   family-clean | family-stribeck | family-gravity: a recording of the recording family
//     (fixtures/recording_family.h), conditions drawn from SEED, none, breakaway friction of
//     the issue-30 size (d_s - d1 = 1.5 N m, w_s = 0.05 rad/s) or a 1 N m gravity imbalance
//     (the datasheet's typical sizes); issue-stribeck: the
//     issue's case (a PD hand, 0.3 N of 1-8 Hz tremor, openings to 60-77 deg, latch, 1 kHz).
//     --hand H, --rate HZ, --sensors S override the drawn conditions; --replay: the data
//     simulated again under the sampled force (RecordingConditions::replay_sampled_force);
//     --datasheet-seed: the recording of the datasheet's draw SEED (studies/loop_datasheet.cpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "analysis/loop/residual_loop.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/simulation/fit_synthetic.h"
#include "fixtures/recording_family.h"
#include "fixtures/simulated_session.h"
#include "fixtures/tremor_recording.h"

using namespace doorbench;

namespace {

DoorModel with_effect(const DoorModel& model, effects::Kind kind, std::vector<double> values) {
  EffectSetting setting{kind, std::move(values), {}};
  for (const effects::EffectParameter& p : effects::info(kind).parameters) {
    setting.bounds.push_back(p.default_bounds);
  }
  return model.with_effect(std::move(setting));
}

// Each stroke's angle range and duration, and its measured speed where it passes a few
// angles (the rate at the first sample past each angle), for seeing which effects a recording
// can excite (a soft close near closed, an end stop near open).
void print_strokes(const PreparedData& data) {
  const double marks_rad[] = {0.3, 0.15, 0.1, 0.05, 1.1, 1.2};
  for (const Stroke& s : data.strokes) {
    if (s.size() == 0) continue;
    double lo = s.theta_rad[0], hi = s.theta_rad[0], fastest = 0.0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      lo = std::min(lo, s.theta_rad[i]);
      hi = std::max(hi, s.theta_rad[i]);
      fastest = std::max(fastest, std::abs(s.omega_rad_s[i]));
    }
    std::printf("stroke %2d %-7s %.2f s  theta %.3f..%.3f rad  |omega| max %.2f rad/s  at:", s.id,
                s.direction == StrokeDirection::kOpening ? "opening" : "closing",
                s.time_s.back() - s.time_s.front(), lo, hi, fastest);
    for (double mark : marks_rad) {
      for (std::size_t i = 1; i < s.size(); ++i) {
        if ((s.theta_rad[i - 1] - mark) * (s.theta_rad[i] - mark) <= 0 &&
            s.theta_rad[i - 1] != s.theta_rad[i]) {
          std::printf("  %.2f: %.3f", mark, s.omega_rad_s[i]);
          break;
        }
      }
    }
    std::printf("\n");
  }
}

// Whether `flag` is among the arguments after CASE.
bool has_flag(int argc, char** argv, const char* flag) {
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], flag) == 0) return true;
  }
  return false;
}

// The tremor hand's options from the arguments: --tremor-mm, --grip, --rest-s, --drift-N.
testing::TremorRecordingOptions recording_options(int argc, char** argv, unsigned seed) {
  testing::TremorRecordingOptions recording;
  recording.seed = seed;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--tremor-mm") == 0 && i + 1 < argc) {
      recording.tremor_amplitude_m = 1e-3 * std::stod(argv[i + 1]);
    }
    if (std::strcmp(argv[i], "--grip") == 0 && i + 1 < argc) {
      recording.grip_stiffness_N_per_m = std::stod(argv[i + 1]);
    }
    if (std::strcmp(argv[i], "--rest-s") == 0 && i + 1 < argc) {
      recording.rest_before_s = std::stod(argv[i + 1]);
    }
    if (std::strcmp(argv[i], "--drift-N") == 0 && i + 1 < argc) {
      recording.drift_force_N = std::stod(argv[i + 1]);
    }
  }
  return recording;
}

// The demo's bench recording (19 s, an undeclared gravity imbalance), prepared.
PreparedData demo_recording(unsigned seed) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("loop_study_" + std::to_string(seed));
  std::filesystem::create_directories(dir);
  const auto effects_path = dir / "undeclared.json";
  std::ofstream(effects_path) << R"({"gravity_imbalance": {"g1": 3.0}})"
                              << "\n";
  const auto session_path = dir / "demo.h5";
  std::filesystem::remove(session_path);
  testing::record_built_in_session(session_path, 19.0, seed, "sensory", effects_path);
  return prepare_session(session_path);
}

// The family cases' conditions: drawn from `seed` (issue-stribeck: the issue's case), then
// the arguments' overrides (--hand, --rate, --sensors).
testing::RecordingConditions family_conditions(const std::string& which, unsigned seed, int argc,
                                               char** argv) {
  testing::RecordingConditions c = testing::draw_conditions(seed);
  if (which == "issue-stribeck") {
    c = testing::RecordingConditions{};
    c.hand = "pd";
    c.tremor_low_hz = 1.0;
    c.tremor_high_hz = 8.0;
    c.tremor_force_N = 0.3;
    c.open_min_rad = 60.0 * kRadPerDeg;
    c.open_max_rad = 77.0 * kRadPerDeg;
    c.sensors = "state";
  }
  for (int i = 2; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--hand") == 0) c.hand = argv[i + 1];
    if (std::strcmp(argv[i], "--rate") == 0) c.sample_rate_hz = std::stod(argv[i + 1]);
    if (std::strcmp(argv[i], "--sensors") == 0) c.sensors = argv[i + 1];
  }
  c.replay_sampled_force = has_flag(argc, argv, "--replay");
  return c;
}

// The recording of the case `which` into `data`; false for an unknown case.
bool make_recording(const std::string& which, const DoorModel& sensory,
                    const testing::TremorRecordingOptions& recording, unsigned seed, int argc,
                    char** argv, PreparedData& data) {
  const double d1 = sensory.parameter_values()[sensory.find_parameter("d1").value()];
  // The catalogue's other effects at the plain-hand tests' sizes, on the tremor hand.
  struct TremorCase {
    const char* name;
    effects::Kind kind;
    std::vector<double> values;
  };
  const TremorCase tremor_cases[] = {
      {"soft-close", effects::Kind::kSoftClose, {5.0, 0.15, 50.0}},
      {"end-stop", effects::Kind::kEndStop, {200.0, 1.2, 3000.0}},
      {"inertia", effects::Kind::kInertiaError, {0.2}},
      {"viscous", effects::Kind::kViscousDamping, {0.5}},
      {"gravity", effects::Kind::kGravityImbalance, {3.0}},
      {"offset", effects::Kind::kForceOffset, {3.0}},
      {"direction", effects::Kind::kDirectionFriction, {1.5}},
  };
  const auto tremor_case = std::find_if(std::begin(tremor_cases), std::end(tremor_cases),
                                        [&](const TremorCase& c) { return which == c.name; });
  if (tremor_case != std::end(tremor_cases)) {
    data = testing::tremor_recording(with_effect(sensory, tremor_case->kind, tremor_case->values),
                                     recording);
  } else if (which == "clean") {
    data = testing::tremor_recording(sensory, recording);
  } else if (which == "stribeck" || which == "stribeck-small" || which == "stribeck-large") {
    const double size = which == "stribeck" ? 1.5 : which == "stribeck-small" ? 0.75 : 3.0;
    data = testing::tremor_recording(
        with_effect(sensory, effects::Kind::kStribeck, {d1 + size, 0.05}), recording);
  } else if (which == "plain-end-stop") {
    // tests/analysis/test_residual_loop.cpp's end-stop recording: the plain virtual hand, 6
    // strokes.
    SyntheticStrokeOptions plain;
    plain.runs = {{0.6, 3.0}, {1.0, 4.0}, {1.3, 4.0}};
    plain.seed = 3;
    data = synthetic_strokes(with_effect(sensory, effects::Kind::kEndStop, {200.0, 1.2, 3000.0}),
                             plain);
  } else if (which == "physical") {
    data = testing::tremor_recording(reference_model(ModelKind::kPhysical), recording);
  } else if (which == "demo") {
    data = demo_recording(seed);
  } else if (which.rfind("family-", 0) == 0 || which == "issue-stribeck") {
    const testing::RecordingConditions c = family_conditions(which, seed, argc, argv);
    const DoorModel truth = which == "family-clean" ? sensory
                            : which == "family-gravity"
                                ? with_effect(sensory, effects::Kind::kGravityImbalance, {1.0})
                                : with_effect(sensory, effects::Kind::kStribeck, {d1 + 1.5, 0.05});
    std::printf("conditions: %s\n", c.describe().c_str());
    // --datasheet-seed: the recording's seed is the draw's, as doorbench_loop_datasheet makes it.
    data = testing::family_recording(truth, c,
                                     has_flag(argc, argv, "--datasheet-seed") ? seed : seed + 1000);
  } else {
    return false;
  }
  return true;
}

// The loop's options from the case and the arguments (--serial, --no-second-look,
// --screen-steps, --min-z, --only), with progress lines timed from now.
LoopOptions loop_options(const std::string& which, int argc, char** argv) {
  LoopOptions options;
  if (which == "inertia") options.fit.fixed_parameters = {"J"};  // else the error is J itself
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--serial") == 0) options.parallel_refits = false;
    if (std::strcmp(argv[i], "--no-second-look") == 0) options.screen_steps = 0;
    if (std::strcmp(argv[i], "--screen-steps") == 0 && i + 1 < argc) {
      options.screen_steps = std::stoi(argv[i + 1]);
    }
    if (std::strcmp(argv[i], "--min-z") == 0 && i + 1 < argc) {
      options.min_score_z = std::stod(argv[i + 1]);
    }
    if (std::strcmp(argv[i], "--substeps") == 0 && i + 1 < argc) {
      options.fit.substeps_per_sample = std::stoi(argv[i + 1]);
    }
    if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
      options.candidates = {effects::find(argv[i + 1]).value()};
    }
  }
  const auto began = std::chrono::steady_clock::now();
  options.progress = [began](const std::string& line) {
    const double t =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    std::printf("[%7.2f s] %s\n", t, line.c_str());
    std::fflush(stdout);
  };
  return options;
}

// --exam: the examination at the base truth, the fit's report, then the examination of
// the fitted model with its speed bands and candidates.
void print_examination(const DoorModel& sensory, const PreparedData& data,
                       const LoopOptions& options) {
  {
    const ResidualExamination at_truth = examine_residual(sensory, data, options);
    std::printf("examination at the base truth (not fitted):\n");
    for (const CandidateEvidence& c : at_truth.candidates) {
      std::printf("  %-18s %6.2f%%  z %6.2f  indep %.3f  %s  start %g\n", c.name.c_str(),
                  100 * c.explained_fraction, c.score_z, c.independent_share, c.scan.c_str(),
                  c.start_values[0]);
    }
  }
  const FitResult fit = fit_model(sensory, data, options.fit);
  std::printf("%s", fit.summary.full_report().c_str());
  const ResidualExamination exam = examine_residual(fit.model, data, options);
  std::printf(
      "examination %.2f s (second look %.2f s); noise floor %.4g rad/s (white %.3g, "
      "walk %.3g per sample)\n",
      exam.time_s, exam.screen_time_s, exam.noise_floor_rad_s, exam.white_noise_rad_s,
      exam.walk_per_sample_rad_s);
  for (const SpeedBand& band : exam.speed_bands) {
    std::printf("  |omega| from %g: %zu samples, residual RMS %.4g rad/s\n", band.low_rad_s,
                band.samples, band.rms_rad_s);
  }
  for (const CandidateEvidence& c : exam.candidates) {
    std::printf("  %-18s %6.2f%%  z %6.2f  indep %.3f  %s  start %g\n", c.name.c_str(),
                100 * c.explained_fraction, c.score_z, c.independent_share, c.scan.c_str(),
                c.start_values.empty() ? 0.0 : c.start_values[0]);
    if (c.screened) {
      std::printf("      second look: %6.2f%%  z %6.2f  values", 100 * c.screen_explained_fraction,
                  c.screen_score_z);
      for (double v : c.screen_values) std::printf(" %g", v);
      std::printf("\n");
    }
  }
}

}  // namespace

// The stages: the arguments, the case's recording, then its strokes (--strokes), the
// examination (--exam) or the whole loop and its report.
int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CASE [SEED] [--exam]\n", argv[0]);
    return 2;
  }
  const std::string which = argv[1];
  const unsigned seed =
      argc > 2 && argv[2][0] != '-' ? static_cast<unsigned>(std::stoul(argv[2])) : 1;
  const bool exam_only = has_flag(argc, argv, "--exam");
  const testing::TremorRecordingOptions recording = recording_options(argc, argv, seed);

  const DoorModel sensory = reference_model(ModelKind::kSensory);
  PreparedData data;
  if (!make_recording(which, sensory, recording, seed, argc, argv, data)) {
    std::fprintf(stderr, "unknown case %s\n", which.c_str());
    return 2;
  }
  std::printf("%s: %zu strokes\n", which.c_str(), data.strokes.size());
  if (has_flag(argc, argv, "--strokes")) {
    print_strokes(data);
    return 0;
  }

  const LoopOptions options = loop_options(which, argc, argv);
  if (exam_only) {
    print_examination(sensory, data, options);
    return 0;
  }
  const LoopResult loop = run_residual_loop(sensory, data, options);
  std::printf("%s", loop.full_report().c_str());
  if (has_flag(argc, argv, "--compare-exam")) {
    // The examination's own objective (measured-state windows, rate residual) at the start
    // fit and at the final model: does it agree with the fit's?
    LoopOptions plain = options;
    plain.screen_steps = 0;
    std::printf("examination sum of squares: start fit %.6g, final model %.6g\n",
                examine_residual(loop.start_fit.model, data, plain).rate_sum_of_squares,
                examine_residual(loop.model(), data, plain).rate_sum_of_squares);
  }
  return 0;
}
