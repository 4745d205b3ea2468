// doorbench spec end to end: TO-BE recordings simulated from a known door (the reference
// door with a softer latch catch), the AS-IS reference door, the report written.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "acquisition/rig/rig_file.h"
#include "analysis/model/parameter_file.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/svg_check.h"

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
  CHECK_THAT(run.err, Contains("tolerance Monte Carlo: 8 of 8 samples, done in "));
  CHECK_THAT(run.out, Contains("What to change: F_l0 15 -> "));
  CHECK_THAT(run.out, Contains("felt along the TO-BE recordings' motion ("));
  CHECK_THAT(run.out, Contains("peak force to unlatch (N)"));
  CHECK_THAT(run.out, Contains("no PDF (not asked for)"));
  // Simulated runs, not a bench's sensors: no warning about --asis-recording.
  CHECK(run.err.find("--asis-recording") == std::string::npos);
  const auto json = nlohmann::json::parse(doorbench::read_text_file(dir / "spec" / "spec.json"));
  CHECK(json["tobe_sources"].size() == 2);
  CHECK(json["tolerances"]["samples"] == 8);
  CHECK(std::filesystem::exists(dir / "spec" / "spec.html"));
  const doorbench::testing::SvgCheck svgs = doorbench::testing::check_svgs({dir / "spec"});
  INFO(svgs.output);
  CHECK(svgs.status == 0);
  CHECK(svgs.legend_entries >= 4);
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

// The inverse design's recipe (docs/inverse-design.md): a prototype (the reference door with the
// spring preload F0 -12 % and the hinge friction T_h +25 %) recorded with `doorbench record` on a
// simulated rig whose door is its file, the AS-IS door recorded on the same bench; `doorbench spec`
// names exactly F0 and T_h (the bench's own damping stays in the AS-IS door).
TEST_CASE("CLI: spec of a bench-recorded prototype against the AS-IS door on the same bench",
          "[cli][spec][slow]") {
  TempDir dir("spec_bench");
  const doorbench::DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  std::vector<double> values(asis.parameter_values().begin(), asis.parameter_values().end());
  values[*asis.find_parameter("F0")] *= 0.88;
  values[*asis.find_parameter("T_h")] *= 1.25;
  const auto asis_file = dir.write("asis.json", doorbench::to_parameter_json(asis));
  dir.write("tobe.json", doorbench::to_parameter_json(asis.with_parameter_values(values)));
  // The built-in rig with the prototype as its door, and with another noise seed.
  std::string rig(doorbench::simulated_dishwasher_rig_text());
  const std::string door_line = "door = \"reference\"";
  const std::string seed_line = "seed = 1 ";
  REQUIRE(rig.find(door_line) != std::string::npos);
  REQUIRE(rig.find(seed_line) != std::string::npos);
  std::string tobe_rig = rig;
  tobe_rig.replace(tobe_rig.find(door_line), door_line.size(), "door = \"tobe.json\"");
  std::string asis_rig = rig;
  asis_rig.replace(asis_rig.find(seed_line), seed_line.size(), "seed = 2 ");
  dir.write("tobe-rig.toml", tobe_rig);
  dir.write("asis-rig.toml", asis_rig);
  for (const char* name : {"tobe", "asis"}) {
    const std::string n(name);
    const auto run =
        run_doorbench_shell("record --rig '" + (dir / (n + "-rig.toml")).string() +
                                "' --duration-s 19 --out '" + (dir / (n + ".h5")).string() + "'",
                            dir);
    INFO(run.err);
    REQUIRE(run.status == 0);
  }
  const auto run = run_doorbench_shell("spec '" + (dir / "tobe.h5").string() + "' --asis '" +
                                           asis_file.string() + "' --asis-recording '" +
                                           (dir / "asis.h5").string() + "' --out '" +
                                           (dir / "spec").string() + "' --samples 8 --no-pdf",
                                       dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Contains("the AS-IS door as this bench sees it: b_h 0.05 -> "));
  const auto json = nlohmann::json::parse(doorbench::read_text_file(dir / "spec" / "spec.json"));
  // The bench seen through its own AS-IS recording: nothing to warn of.
  CHECK(run.err.find("warning: the TO-BE recording") == std::string::npos);
  CHECK(json["warnings"].empty());
  CHECK(json["fit"]["parts_changed"] == 2);
  for (const auto& p : json["parameters"]) {
    const std::string name = p["name"];
    INFO(name << ": " << p.dump());
    if (name == "F0" || name == "T_h") {
      CHECK(p["changed"] == true);
      const double truth = name == "F0" ? 220.0 : 0.75;
      CHECK(std::abs(p["to_be"].get<double>() - truth) <=
            0.05 * std::abs(truth - p["as_is"].get<double>()));
    } else {
      CHECK(p["changed"] == false);
    }
  }
  CHECK_THAT(run.out, Contains("What to change: F0 250 -> "));
}

// A TO-BE recording of a real door through a bench's sensors, without --asis-recording: the
// spec warns, naming the risk and the option, on stderr and in spec.json.
TEST_CASE("CLI: spec warns when a bench recording is specified without --asis-recording",
          "[cli][spec]") {
  TempDir dir("spec_bench_warning");
  const std::string tobe = (dir / "tobe.h5").string();
  REQUIRE(run_doorbench_shell("record --duration-s 8 --out '" + tobe + "'", dir).status == 0);
  const auto asis_file = dir.write(
      "asis.json",
      doorbench::to_parameter_json(doorbench::reference_model(doorbench::ModelKind::kPhysical)));
  const std::string warning =
      "the TO-BE recording " + tobe +
      " was measured through a bench's sensors (angle: rate_rad_s integrated, anchored to "
      "inclinometer_angle_rad) and --asis-recording is not given: the AS-IS parameter file is "
      "compared with what the bench measured, so the bench's own deviations (sensor offsets "
      "and scales, the load cell's mounting, its friction) can be specified as design changes; "
      "record the AS-IS door on the same bench and give it as --asis-recording";
  const auto run =
      run_doorbench_shell("spec '" + tobe + "' --asis '" + asis_file.string() + "' --out '" +
                              (dir / "spec").string() + "' --samples 2 --starts 1 --no-pdf",
                          dir);
  INFO("stderr: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Contains("\nwarning: " + warning + "\n"));
  const auto json = nlohmann::json::parse(doorbench::read_text_file(dir / "spec" / "spec.json"));
  CHECK(json["warnings"] == nlohmann::json::array({warning}));
  CHECK_THAT(doorbench::read_text_file(dir / "spec" / "spec.html"),
             Contains("<p class=\"bad\">Warning: the TO-BE recording "));
}
