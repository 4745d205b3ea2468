// doorbench spec end to end: TO-BE recordings simulated from a known door (the reference
// door with a softer latch catch), the AS-IS reference door, the report written.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "analysis/parameter_file.h"
#include "tests/run_doorbench.h"

using Catch::Matchers::Contains;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

TEST_CASE("CLI: spec from simulated TO-BE recordings", "[cli][spec]") {
  TempDir dir("spec_cli");
  const doorbench::DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  std::vector<double> values(asis.parameter_values().begin(), asis.parameter_values().end());
  values[doorbench::physical::kFl0] *= 0.7;
  const doorbench::DoorModel tobe = asis.with_parameter_values(values);
  const auto asis_file = dir.write("asis.json", doorbench::to_parameter_json(asis));
  const auto tobe_file = dir.write("tobe.json", doorbench::to_parameter_json(tobe));
  for (const char* target : {"60", "80"}) {
    const auto run =
        run_doorbench_shell(std::string("simulate --model physical --params '")
                                .append(tobe_file.string())
                                .append("' --hand open-close --target-deg ")
                                .append(target)
                                .append(" --duration-s 6 --out '")
                                .append((dir / (std::string("tobe") + target + ".csv")).string())
                                .append("'"),
                            dir);
    REQUIRE(run.status == 0);
  }
  const auto run = run_doorbench_shell(std::string("spec '")
                                           .append((dir / "tobe60.csv").string())
                                           .append("' '")
                                           .append((dir / "tobe80.csv").string())
                                           .append("' --asis '")
                                           .append(asis_file.string())
                                           .append("' --out '")
                                           .append((dir / "spec").string())
                                           .append("' --samples 8 --starts 1 --no-pdf"),
                                       dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Contains("tolerance Monte Carlo: 8 / 8 samples"));
  CHECK_THAT(run.out, Contains("What to change: F_l0 15 -> "));
  CHECK_THAT(run.out, Contains("felt along the TO-BE recordings' motion ("));
  CHECK_THAT(run.out, Contains("peak force to unlatch (N)"));
  CHECK_THAT(run.out, Contains("no PDF (not asked for)"));
  const auto json = nlohmann::json::parse(doorbench::read_text_file(dir / "spec" / "spec.json"));
  CHECK(json["tobe_sources"].size() == 2);
  CHECK(json["tolerances"]["samples"] == 8);
  CHECK(std::filesystem::exists(dir / "spec" / "spec.html"));
  CHECK(std::filesystem::exists(dir / "spec" / "tobe-params.json"));
  // The design moves F_l0 toward the TO-BE door's (10.5 N from 15 N).
  const auto& f_l0 = json["parameters"][doorbench::physical::kFl0];
  CHECK(f_l0["name"] == "F_l0");
  CHECK(f_l0["to_be"].get<double>() < 13.0);
  CHECK(json["check"]["after"]["curve_rms_error_N"].get<double>() <
        json["check"]["before"]["curve_rms_error_N"].get<double>());

  // Wrong inputs are named.
  const auto bad_cost = run_doorbench_shell(std::string("spec '")
                                                .append((dir / "tobe60.csv").string())
                                                .append("' --asis '")
                                                .append(asis_file.string())
                                                .append("' --costs F0 --out '")
                                                .append((dir / "spec3").string())
                                                .append("'"),
                                            dir);
  CHECK(bad_cost.status != 0);
  CHECK_THAT(bad_cost.err, Contains("--costs: 'F0' is not NAME=COST (e.g. F0=1)"));
  const auto missing = run_doorbench_shell(std::string("spec '")
                                               .append((dir / "tobe60.csv").string())
                                               .append("' --asis '")
                                               .append((dir / "nope").string())
                                               .append("' --out '")
                                               .append((dir / "spec2").string())
                                               .append("'"),
                                           dir);
  CHECK(missing.status == 1);
  CHECK_THAT(missing.err,
             Contains("nope/fitted-params.json: no such file") || Contains("nope: no such file"));
}
