// Identifiable parameters: a fit that leaves parameters undetermined
// proposes the free set the data determine, and `doorbench fit --free auto` fits that set,
// holding the rest at their start values and saying so. The recording: a robot turns the
// door at constant speed through its free range, pushing exactly the door's own torque, so
// the door never accelerates and its inertia acts only through the force sensor's noise;
// the latch is never reached.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "acquisition/session/recording_csv.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "core/number_format.h"
#include "core/units.h"
#include "fixtures/recording_family.h"
#include "fixtures/reference_doors.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/robot_recording.h"
#include "tests/support/run_doorbench.h"

namespace {

using namespace doorbench;

// Four strokes between 0.4 and 1.2 rad at ±0.4 rad/s, 1 kHz: the reference sensory door,
// the force exactly -τ_m / r_h, all without noise. (With the bench's noise J is determined:
// a window started off the measured state relaxes back at the rate (∂τ_m/∂ω)/J, and the
// window's response to the load cell's noise depends on J too.)
Recording constant_speed_recording() {
  const DoorModel door = reference_model(ModelKind::kSensory);
  const double radius_m = door.geometry().handle_radius_m;
  Recording recording;
  recording.source = "constant speed";
  recording.angle_rad.emplace();
  recording.rate_rad_s.emplace();
  recording.stroke.emplace();
  double terms[DoorModel::kMaxTerms];
  constexpr double kSpeed_rad_s = 0.4, kLow = 0.4, kHigh = 1.2, kRate_hz = 1000.0;
  const int samples = static_cast<int>(std::lround((kHigh - kLow) / kSpeed_rad_s * kRate_hz));
  for (int stroke = 0; stroke < 4; ++stroke) {
    const bool opening = stroke % 2 == 0;
    const double omega = opening ? kSpeed_rad_s : -kSpeed_rad_s;
    for (int i = 0; i < samples; ++i) {
      const double t = (stroke * samples + i) / kRate_hz;
      const double theta =
          opening ? kLow + kSpeed_rad_s * i / kRate_hz : kHigh - kSpeed_rad_s * i / kRate_hz;
      const double torque = door.evaluate(door.parameter_values().data(), theta, omega, terms);
      recording.time_s.push_back(t);
      recording.force_N.push_back(-torque / radius_m);
      recording.angle_rad->push_back(theta);
      recording.rate_rad_s->push_back(omega);
      recording.stroke->push_back(stroke + 1);
    }
  }
  return recording;
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

TEST_CASE("Identifiable parameters: the proposal leaves out what the data cannot determine",
          "[fitting][identifiable]") {
  const PreparedData data = prepare(constant_speed_recording());
  REQUIRE(data.strokes.size() == 4);
  FitOptions options;
  options.cross_validation_folds = 0;
  const DoorModel start = reference_model(ModelKind::kSensory);
  const FitResult full = fit_model(start, data, options);
  const FitSummary& s = full.summary;
  INFO(s.brief_report());
  CHECK(contains(s.undetermined, "J"));
  REQUIRE(!s.identifiable.empty());
  CHECK(!contains(s.identifiable, "J"));
  for (const std::string& name : s.identifiable) CHECK(contains(s.free_names, name));
  CHECK(s.brief_report().find(s.identifiable_line()) != std::string::npos);
  // The proposal fitted: every parameter determined.
  options.free_parameters = s.identifiable;
  const FitResult proposed = fit_model(start, data, options);
  INFO(proposed.summary.brief_report());
  CHECK(proposed.summary.undetermined.empty());
  CHECK(proposed.summary.identifiable.empty());
  CHECK(proposed.summary.identifiable_line().empty());
}

TEST_CASE("doorbench fit --free auto fits the identifiable set and holds the rest",
          "[cli][fit][identifiable]") {
  const testing::TempDir dir("free_auto");
  const auto csv = dir / "constant-speed.csv";
  write_recording_csv_file(csv, constant_speed_recording());
  const auto out = dir / "fit";
  const testing::DoorbenchRun run = testing::run_doorbench_shell(
      "fit '" + csv.string() + "' --start file --folds 0 --free auto --out '" + out.string() + "'",
      dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const std::string line =
      "--free auto: the default free set leaves 10 of its 13 parameters undetermined (J, k, "
      "k_inf, k_lock, theta0, theta1, theta2, theta3, c, s); fitting the 3 the data determine "
      "with the others held (from the Jacobian's singular vectors at its optimum): d1, d2, "
      "theta4; held at the full fit's values: J, k, k_inf, k_lock, theta0, theta1, theta2, "
      "theta3, c, s";
  CHECK(run.err.find("\n" + line + "\n") != std::string::npos);
  const std::string report = testing::read_file(out / "report.md");
  CHECK(report.find("\n\n" + line + ".\n\n") != std::string::npos);
  const nlohmann::json result = nlohmann::json::parse(testing::read_file(out / "result.json"));
  CHECK(result.at("undetermined").empty());
  CHECK(result.at("free_parameters").get<int>() == 3);
  // J is held at the full fit's value: the default free set fitted as `fit` fits it.
  const PreparedData data = prepare(constant_speed_recording());
  FitOptions options;
  options.cross_validation_folds = 0;
  const FitResult full = fit_model(reference_model(ModelKind::kSensory), data, options);
  const double full_j = full.model.parameter_values()[*full.model.find_parameter("J")];
  CHECK(full_j != reference_model(ModelKind::kSensory).parameter_values()[0]);
  for (const auto& p : result.at("parameters")) {
    if (p.at("name") != "J") continue;
    CHECK(!p.at("free").get<bool>());
    CHECK(p.at("value").get<double>() == Approx(full_j).epsilon(1e-6));  // the full fit's
  }
}

// A recording like one from another lab (50 Hz, jittered, 4 strokes, a robot operator, a load
// cell not tared, the handle at 0.8 m): held at the full fit's values, the identifiable set
// ends within 2 FIT points of the full fit, and the report says what holding them costs.
// `--no-reset` on the same recording leaves out the reset start, `--repolish 0` the polishes of
// the best optimum again, `--no-soft` the fits with softer switches.
TEST_CASE(
    "doorbench fit --free auto on the robot recording stays within 2 FIT points of the "
    "full fit",
    "[cli][fit][identifiable][slow]") {
  const testing::TempDir dir("free_auto_robot");
  const auto csv = dir / "robot.csv";
  write_recording_csv_file(
      csv, testing::family_sensor_recording(testing::robot_door(),
                                            testing::robot_operator_conditions(), 42));
  auto run_fit = [&](const std::string& extra, const std::string& name) {
    const testing::DoorbenchRun run = testing::run_doorbench_shell(
        "fit '" + csv.string() + "' --folds 0 " + extra + " --out '" + (dir / name).string() + "'",
        dir);
    INFO(run.err);
    REQUIRE(run.status == 0);
    return std::make_pair(run.err,
                          nlohmann::json::parse(testing::read_file(dir / name / "result.json")));
  };
  const auto [full_err, full] = run_fit("", "full");
  const auto [auto_err, proposed] = run_fit("--free auto", "auto");
  INFO(auto_err);
  const double full_fit = full.at("fitted").at("windows").at("fit_percent").get<double>();
  const double auto_fit = proposed.at("fitted").at("windows").at("fit_percent").get<double>();
  CHECK(auto_fit >= full_fit - 2.0);
  CHECK(proposed.at("free_parameters").get<int>() < full.at("free_parameters").get<int>());
  // What holding the others costs, said as measured.
  const std::string cost_line =
      "--free auto: holding the others costs " + printf_text("%.2f", full_fit - auto_fit) +
      " points of window FIT (the full fit " + printf_text("%.2f%%", full_fit) + ", this fit " +
      printf_text("%.2f%%", auto_fit) + ")";
  CHECK(auto_err.find("\n" + cost_line + "\n") != std::string::npos);
  // --no-reset leaves out the reset start (and the rounds its polish would have begun).
  const auto [plain_err, plain] = run_fit("--no-reset", "no-reset");
  const nlohmann::json& tried = full.at("global_search");
  const nlohmann::json& plain_tried = plain.at("global_search");
  CHECK(tried.at("reset_parameters").get<int>() > 0);
  CHECK(plain_tried.at("reset_parameters").get<int>() == 0);
  CHECK(plain_tried.at("starts_tried").get<int>() < tried.at("starts_tried").get<int>());
  CHECK(testing::read_file(dir / "full" / "report.md").find("at their starts") !=
        std::string::npos);
  CHECK(testing::read_file(dir / "no-reset" / "report.md").find("at their starts") ==
        std::string::npos);
  // --repolish 0 leaves out the polishes of the best optimum from its own values.
  const auto [unpolished_err, unpolished] = run_fit("--repolish 0", "repolish-0");
  const nlohmann::json& unpolished_tried = unpolished.at("global_search");
  CHECK(tried.at("repolished").get<int>() > 0);
  CHECK(unpolished_tried.at("repolished").get<int>() == 0);
  CHECK(unpolished_tried.at("starts_tried").get<int>() < tried.at("starts_tried").get<int>());
  CHECK(testing::read_file(dir / "full" / "report.md").find("from its own values") !=
        std::string::npos);
  CHECK(testing::read_file(dir / "repolish-0" / "report.md").find("from its own values") ==
        std::string::npos);
  // --no-soft leaves out the fits with softer switches.
  const auto [hard_err, hard] = run_fit("--no-soft", "no-soft");
  const nlohmann::json& hard_tried = hard.at("global_search");
  CHECK(tried.at("soft_starts").get<int>() == 2);
  CHECK(hard_tried.at("soft_starts").get<int>() == 0);
  CHECK(hard_tried.at("starts_tried").get<int>() == tried.at("starts_tried").get<int>() - 2);
  CHECK(testing::read_file(dir / "full" / "report.md").find("softer switches") !=
        std::string::npos);
  CHECK(testing::read_file(dir / "no-soft" / "report.md").find("softer switches") ==
        std::string::npos);
}
