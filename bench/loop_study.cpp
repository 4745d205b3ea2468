// Not a timing: runs the residual loop on one recording made by the tremor hand
// (tests/support/tremor_recording.h) or on the demo's bench recording, and prints the progress
// lines (each fit with its time), the examination's ranking and the full report, for
// docs/residual-loop.md and docs/PERFORMANCE.md.
//
//   doorbench_loop_study CASE [SEED] [--exam]
//   CASE: clean | stribeck | stribeck-small | stribeck-large | physical | demo | plain-end-stop
//   --exam: the examination of the true-model-less fit only (no refits)
//   --serial: refits one after another; --no-second-look: screen_steps = 0
//   --tremor-mm A, --drift-N F: the tremor hand's amplitudes (defaults 0.5 mm, 1 N)
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "analysis/fit_synthetic.h"
#include "analysis/parameter_file.h"
#include "analysis/preprocessing.h"
#include "analysis/residual_loop.h"
#include "tests/support/simulated_session.h"
#include "tests/support/tremor_recording.h"

using namespace doorbench;

namespace {

DoorModel with_effect(const DoorModel& model, effects::Kind kind, std::vector<double> values) {
  EffectSetting setting{kind, std::move(values), {}};
  for (const effects::EffectParameter& p : effects::info(kind).parameters) {
    setting.bounds.push_back(p.default_bounds);
  }
  return model.with_effect(std::move(setting));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CASE [SEED] [--exam]\n", argv[0]);
    return 2;
  }
  const std::string which = argv[1];
  const unsigned seed = argc > 2 && argv[2][0] != '-' ? static_cast<unsigned>(std::stoul(argv[2])) : 1;
  bool exam_only = false;
  testing::TremorRecordingOptions recording;
  recording.seed = seed;
  for (int i = 2; i < argc; ++i) {
    exam_only = exam_only || std::strcmp(argv[i], "--exam") == 0;
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

  const DoorModel sensory = reference_model(ModelKind::kSensory);
  const double d1 = sensory.parameter_values()[sensory.find_parameter("d1").value()];
  PreparedData data;
  if (which == "clean") {
    data = testing::tremor_recording(sensory, recording);
  } else if (which == "stribeck" || which == "stribeck-small" || which == "stribeck-large") {
    const double size = which == "stribeck" ? 1.5 : which == "stribeck-small" ? 0.75 : 3.0;
    data = testing::tremor_recording(
        with_effect(sensory, effects::Kind::kStribeck, {d1 + size, 0.05}), recording);
  } else if (which == "plain-end-stop") {
    // tests/analysis/test_residual_loop.cpp's end-stop recording: the plain virtual hand, 6 strokes.
    SyntheticStrokeOptions plain;
    plain.runs = {{0.6, 3.0}, {1.0, 4.0}, {1.3, 4.0}};
    plain.seed = 3;
    data = synthetic_strokes(with_effect(sensory, effects::Kind::kEndStop, {200.0, 1.2, 3000.0}),
                             plain);
  } else if (which == "physical") {
    data = testing::tremor_recording(reference_model(ModelKind::kPhysical), recording);
  } else if (which == "demo") {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("loop_study_" + std::to_string(seed));
    std::filesystem::create_directories(dir);
    const auto effects_path = dir / "undeclared.json";
    std::ofstream(effects_path) << R"({"gravity_imbalance": {"g1": 3.0}})" << "\n";
    const auto session_path = dir / "demo.h5";
    std::filesystem::remove(session_path);
    testing::record_built_in_session(session_path, 19.0, seed, "sensory", effects_path);
    data = prepare_session(session_path);
  } else {
    std::fprintf(stderr, "unknown case %s\n", which.c_str());
    return 2;
  }
  std::printf("%s: %zu strokes\n", which.c_str(), data.strokes.size());

  LoopOptions options;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--serial") == 0) options.parallel_refits = false;
    if (std::strcmp(argv[i], "--no-second-look") == 0) options.screen_steps = 0;
  }
  const auto began = std::chrono::steady_clock::now();
  options.progress = [&](const std::string& line) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    std::printf("[%7.2f s] %s\n", t, line.c_str());
    std::fflush(stdout);
  };
  if (exam_only) {
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
    std::printf("examination %.2f s (second look %.2f s); noise floor %.4g rad/s (white %.3g, "
                "walk %.3g per sample)\n",
                exam.time_s, exam.screen_time_s, exam.noise_floor_rad_s, exam.white_noise_rad_s,
                exam.walk_per_sample_rad_s);
    for (const SpeedBand& band : exam.speed_bands) {
      std::printf("  |omega| from %g: %zu samples, residual RMS %.4g rad/s\n", band.low_rad_s,
                  band.samples, band.rms_rad_s);
    }
    for (const CandidateEvidence& c : exam.candidates) {
      std::printf("  %-18s %6.2f%%  z %6.2f  indep %.3f  %s\n", c.name.c_str(),
                  100 * c.explained_fraction, c.score_z, c.independent_share, c.scan.c_str());
      if (c.screened) {
        std::printf("      second look: %6.2f%%  z %6.2f  values", 100 * c.screen_explained_fraction,
                    c.screen_score_z);
        for (double v : c.screen_values) std::printf(" %g", v);
        std::printf("\n");
      }
    }
    return 0;
  }
  const LoopResult loop = run_residual_loop(sensory, data, options);
  std::printf("%s", loop.full_report().c_str());
  return 0;
}
