// `doorbench view --fit DIR`: a real `doorbench fit` output folder (result.json and the
// fitted parameter file) read as the viewer's fit result, its model the fitted one, and
// the fit layout drawn with it under Xvfb; the messages for folders that are not one.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "analysis/fit/fit_result_file.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

// Runs the doorbench executable (optionally under xvfb-run); exit code and stderr.
std::pair<int, std::string> run_doorbench(const std::string& arguments, const fs::path& dir,
                                          bool xvfb = false) {
  const fs::path err = dir / "stderr.txt";
  const std::string command = std::string(xvfb ? "xvfb-run -a -s '-screen 0 1024x768x24' " : "")
                                  .append(DOORBENCH_EXECUTABLE)
                                  .append(" ")
                                  .append(arguments)
                                  .append(" >/dev/null 2>")
                                  .append(err.string());
  const int status = std::system(command.c_str());
  std::ifstream in(err);
  std::ostringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

}  // namespace

TEST_CASE("view --fit takes a doorbench fit folder as the fit result", "[viewer][xvfb]") {
  doorbench::testing::TempDir dir("viewer_fit_result");
  const fs::path session = dir.path / "bench.h5";
  doorbench::testing::record_built_in_session(session, 12.0, 3, "sensory");
  const fs::path out = dir.path / "fit";
  // A small real fit (two free parameters) so that the test stays short.
  auto [fit_code, fit_err] = run_doorbench(
      "fit " + session.string() + " --model sensory --folds 0 --free k,d1 --out " + out.string(),
      dir.path);
  INFO("fit stderr: " << fit_err);
  REQUIRE(fit_code == 0);

  const doorbench::FitResultFolder fit = doorbench::read_fit_result(out);
  REQUIRE(fit.model_kind == doorbench::ModelKind::kSensory);
  REQUIRE_THAT(fit.source, Contains("bench.h5"));
  REQUIRE(fit.strokes > 0);
  REQUIRE(std::isfinite(fit.fitted_window_rmse_rad_s));
  REQUIRE(std::isnan(fit.held_out_window_rmse_rad_s));  // --folds 0
  REQUIRE(fit.params_path == out / "fitted-params.json");
  REQUIRE(fit.effects_path.empty());
  // The model is the fitted one (not the reference door it started from).
  const doorbench::DoorModel written =
      doorbench::load_model(doorbench::ModelKind::kSensory, out / "fitted-params.json", "");
  const doorbench::DoorModel reference = doorbench::reference_model(doorbench::ModelKind::kSensory);
  bool differs_from_start = false;
  for (int i = 0; i < written.parameter_count(); ++i) {
    REQUIRE(fit.model.parameter_values()[std::size_t(i)] ==
            written.parameter_values()[std::size_t(i)]);
    differs_from_start |=
        written.parameter_values()[std::size_t(i)] != reference.parameter_values()[std::size_t(i)];
  }
  REQUIRE(differs_from_start);
  const std::string description = fit.description();
  REQUIRE_THAT(description, Contains("sensory fit"));
  REQUIRE_THAT(description, Contains(out.string()));
  REQUIRE_THAT(description, Contains(fit.converged ? "(converged" : "NOT converged"));

  // The fit layout, drawn for real: its plot is titled by the fit result.
  const fs::path png = dir.path / "fit.png";
  auto [view_code, view_err] = run_doorbench("view --screenshot " + png.string() +
                                                 " --layout fit --width 900 --height 600 --fit " +
                                                 out.string() + " " + session.string(),
                                             dir.path, true);
  INFO("view stderr: " << view_err);
  REQUIRE(view_code == 0);
  std::ifstream info_file(png.string() + ".json");
  const nlohmann::json info = nlohmann::json::parse(info_file);
  // Rate, residual and the residual's whiteness.
  REQUIRE(info["plots"].size() == 3);
  REQUIRE_THAT(info["plots"][2]["title"].get<std::string>(),
               Contains("residual whiteness (99 % band): residual autocorrelation: "));
  REQUIRE_THAT(info["plots"][0]["title"].get<std::string>(), Contains(description));

  // --fit gives the model: not with --params.
  auto [both_code, both_err] = run_doorbench(
      "view --screenshot " + png.string() + " --layout fit --fit " + out.string() + " --params " +
          (out / "fitted-params.json").string() + " " + session.string(),
      dir.path);
  REQUIRE(both_code == 2);
  REQUIRE_THAT(both_err, Contains("--fit gives the model"));
}

TEST_CASE("read_fit_result names the file and field it cannot use", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_fit_result_errors");
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path / "nowhere"), Contains("not a folder"));
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path), Contains("result.json: cannot open"));
  std::ofstream(dir.path / "result.json") << "{\"steps\": []}";
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path),
                      Contains("a `doorbench loop` result; open it with --loop"));
  std::ofstream(dir.path / "result.json") << "{\"model\": \"wooden\"}";
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path),
                      Contains("'model' is not sensory or physical"));
  std::ofstream(dir.path / "result.json") << "{\"model\": \"sensory\"}";
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path),
                      Contains("fitted-params.json: missing"));
  std::ofstream(dir.path / "fitted-params.json")
      << doorbench::to_parameter_json(doorbench::reference_model(doorbench::ModelKind::kSensory));
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path),
                      Contains("result.json: no field 'source'"));
  std::ofstream(dir.path / "result.json")
      << R"({"model": "sensory", "source": "s.h5", "converged": true, "termination": "x",
             "strokes": 4, "fitted": {"windows": {"rmse_rad_s": 0.5}}})";
  REQUIRE_THROWS_WITH(doorbench::read_fit_result(dir.path),
                      Contains("result.json: no field 'held_out'"));
  std::ofstream(dir.path / "result.json")
      << R"({"model": "sensory", "source": "s.h5", "converged": true, "termination": "x",
             "strokes": 4, "fitted": {"windows": {"rmse_rad_s": 0.5}}, "held_out": null})";
  const auto fit = doorbench::read_fit_result(dir.path);
  REQUIRE(fit.fitted_window_rmse_rad_s == 0.5);
  REQUIRE(fit.strokes == 4);
  REQUIRE_THAT(fit.description(), Contains("4 strokes, window RMSE 0.5 rad/s fitted)"));
}
