// Calibration records, the store, rigs naming records, applying a record to a session
// (raw samples unchanged, physical values and delay from the record), the certificate
// and the calibrate/calibration verbs.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/calibration_store.h"
#include "acquisition/session/session_csv.h"
#include "calibration/certificate.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "sensors/rig_channel.h"
#include "tests/support/files.h"
#include "tests/support/svg_check.h"

using doorbench::testing::read_file;

using namespace doorbench;
using namespace doorbench::calibration;

namespace {

CalibrationRecord full_record() {
  CalibrationRecord r;
  r.id = "load_cell-LC-7-v2";
  r.version = 2;
  r.sensor_kind = "load_cell";
  r.sensor_serial = "LC-7";
  r.unit = "N";
  r.coefficients = {-1.5, 44.4, -0.002};
  r.standard_uncertainty = 0.07;
  r.method = "multi-point";
  r.date_utc = "2026-11-21T10:00:00Z";
  r.operator_name = "Zoë";
  r.supersedes = "load_cell-LC-7-v1";
  r.references = "M1 masses";
  r.points = {{0.0, 0.03, 0.004, 1000, 0.01, "loading"},
              {98.0665, 2.24, 0.004, 1000, -0.02, "unloading"}};
  r.quantities = {{"gain_N_per_V", 44.4, 0.03, "N/V"}};
  r.delay_s = 0.0154;
  r.delay_standard_uncertainty_s = 0.0002;
  r.valid_min = 0.0;
  r.valid_max = 445.0;
  return r;
}

}  // namespace

TEST_CASE("Calibration record: every field survives the JSON round trip", "[calibration][record]") {
  const CalibrationRecord r = full_record();
  const CalibrationRecord back = calibration_record_from_json(to_json(r), "test");
  CHECK(to_json(back) == to_json(r));
  CHECK(back.points.size() == 2);
  CHECK(back.points[1].branch == "unloading");
  CHECK(back.quantity("gain_N_per_V")->standard_uncertainty == 0.03);
  CHECK(back.delay_s == 0.0154);
  CHECK(back.valid_max == 445.0);
  CHECK(back.supersedes == "load_cell-LC-7-v1");
  // A record without the new fields keeps its short form (and infinite range).
  CalibrationRecord plain;
  plain.id = "x";
  plain.unit = "N";
  plain.coefficients = {0, 1};
  CHECK(to_json(plain).find("points") == std::string::npos);
  CHECK(std::isinf(calibration_record_from_json(to_json(plain), "t").valid_max));
  CHECK_THROWS_WITH(calibration_record_from_json(
                        R"({"id":"x","unit":"N","coefficients":[0,1],"points":[1]})", "f.json"),
                    "f.json: points must be an array of objects");
}

TEST_CASE("Calibration store: add, find, latest, versions, and records never change",
          "[calibration][store]") {
  testing::TempDir dir("calibration_store");
  const CalibrationStore store(dir / "store");
  CHECK(store.records().empty());
  CHECK(store.next_version("load_cell", "LC-7") == 1);
  CalibrationRecord r = full_record();
  CHECK(store.add(r) == dir / "store" / "load_cell-LC-7-v2.json");
  CHECK(store.add(r) == dir / "store" / "load_cell-LC-7-v2.json");  // the same again: fine
  CalibrationRecord changed = r;
  changed.coefficients[0] = -1.4;
  CHECK_THROWS_WITH(store.add(changed),
                    Catch::EndsWith("the store already holds a different record "
                                    "load_cell-LC-7-v2 (records are never changed: make a new "
                                    "version)"));
  CalibrationRecord v3 = r;
  v3.version = 3;
  v3.id = make_record_id("load_cell", "LC-7", 3);
  store.add(v3);
  CHECK(store.latest("load_cell", "LC-7")->id == "load_cell-LC-7-v3");
  CHECK(store.next_version("load_cell", "LC-7") == 4);
  CHECK(make_record_id("gyroscope", "A/B 1", 2) == "gyroscope-A_B_1-v2");
  CHECK_THROWS_WITH(store.get("nope"), "no calibration record nope in " + (dir / "store").string() +
                                           " (2 records: load_cell-LC-7-v2, load_cell-LC-7-v3)");
  CHECK(resolve_channel_record(store, "latest", "force", "load_cell", "LC-7", "N").id ==
        "load_cell-LC-7-v3");
  CHECK_THROWS_WITH(
      resolve_channel_record(store, "load_cell-LC-7-v2", "force", "load_cell", "LC-8", "N"),
      "channel force: calibration record load_cell-LC-7-v2 calibrates sensor LC-7, "
      "not LC-8");
  CHECK_THROWS_WITH(resolve_channel_record(store, "latest", "rate", "gyroscope", "G-1", "rad/s"),
                    Catch::EndsWith(" holds no record for gyroscope G-1 (calibrate it first)"));
  CHECK(calibration_store_directory("/x", "/rig") == "/x");
}

TEST_CASE("Calibration record: an expiry that is not an ISO 8601 date is refused on read",
          "[calibration][record]") {
  testing::TempDir dir("calibration_expiry");
  const auto file = dir.write("store/x.json", R"({"id":"x","unit":"N","coefficients":[0,1],)"
                                              R"("valid_until_utc":"notadate"})");
  const CalibrationStore store(dir / "store");
  const std::string refusal =
      file.string() +
      ": calibration record x: valid_until_utc: notadate is not an ISO 8601 date (YYYY-MM-DD, "
      "or YYYY-MM-DDTHH:MM:SSZ in UTC)";
  CHECK_THROWS_WITH(store.records(), refusal);
  CHECK_THROWS_WITH(store.get("x"), refusal);
  CHECK_THROWS_WITH(calibration_record_from_json(R"({"id":"y","unit":"N","coefficients":[0,1],)"
                                                 R"("valid_until_utc":"2099-02-29"})",
                                                 "y.json"),
                    "y.json: calibration record y: valid_until_utc: 2099-02-29 is not a day of "
                    "the calendar");
  CalibrationRecord r = full_record();
  r.valid_until_utc = "2099-12-31";
  CHECK(r.validate().empty());
  r.valid_until_utc = "";  // no expiry
  CHECK(r.validate().empty());
  r.valid_until_utc = "31.12.2099";
  CHECK(r.validate() ==
        "calibration record load_cell-LC-7-v2: valid_until_utc: 31.12.2099 is "
        "not an ISO 8601 date (YYYY-MM-DD, or YYYY-MM-DDTHH:MM:SSZ in UTC)");
  CHECK_THROWS_WITH(CalibrationStore(dir / "other").add(r),
                    Catch::Contains("valid_until_utc: 31.12.2099 is not an ISO 8601 date"));
}

TEST_CASE("Calibration record: a new record's expiry is on the calendar and not before today",
          "[calibration][record]") {
  const std::string now = "2026-11-29T00:30:15Z";
  CHECK(new_valid_until_problem("2026-11-29", now).empty());
  CHECK(new_valid_until_problem("2026-11-29T00:00Z", now).empty());
  CHECK(new_valid_until_problem("2027-01-01T12:00:00Z", now).empty());
  CHECK(new_valid_until_problem("2026-11-28T23:59:59Z", now) ==
        "2026-11-28T23:59:59Z is before today (2026-11-29): the record would have expired when "
        "made");
  CHECK(new_valid_until_problem("2026-13-01", now) == "2026-13-01 is not a day of the calendar");
  CHECK(new_valid_until_problem("tomorrow", now) ==
        "tomorrow is not an ISO 8601 date (YYYY-MM-DD, or YYYY-MM-DDTHH:MM:SSZ in UTC)");
}

TEST_CASE("Rig channels name records of the store, and sessions carry them in full",
          "[calibration][store]") {
  testing::TempDir dir("calibration_rig_store");
  std::string text(simulated_dishwasher_rig_text());
  const std::string nominal = "calibration = \"nominal\"";
  text.replace(text.find(nominal), nominal.size(), "calibration = \"latest\"");
  RigDefinition rig = parse_rig(text, "rig.toml", dir.path);
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  // No record yet in dir/calibrations (the default store beside the rig).
  CHECK_THROWS_WITH(simulated_bench::SimulatedBench(rig, model, 1.0),
                    Catch::StartsWith("rig.toml: channel force: calibration \"latest\": ") &&
                        Catch::EndsWith("holds no record for load_cell SIM-LC445-0001 "
                                        "(calibrate it first)"));
  CalibrationRecord r = sensors::nominal_calibration(rig.channels[0]);
  r.id = make_record_id("load_cell", "SIM-LC445-0001", 1);
  r.coefficients = {-0.5, 44.6};
  r.method = "multi-point";
  rig.calibration_store = dir / "elsewhere";
  CalibrationStore(rig.calibration_store).add(r);
  simulated_bench::SimulatedBench bench(rig, model, 1.0);
  SessionMetadata metadata;
  metadata.rig_name = rig.name;
  RecordOptions options;
  options.duration_s = 1.0;
  record_session(bench, metadata, dir / "s.h5", options);
  const SessionReader session(dir / "s.h5");
  CHECK(session.channel("force").calibration_id == r.id);
  CHECK(to_json(session.calibrations()[0]) == to_json(r));
}

TEST_CASE("Applying a record to a session: raw unchanged, values and delay from the record",
          "[calibration][apply]") {
  testing::TempDir dir("calibration_apply");
  const auto path = dir / "s.h5";
  testing::record_built_in_session(path, 3.0, 1);
  // A session being written to must not be open for reading: readers live in blocks.
  ChannelSlice raw_before;
  std::vector<double> physical_before;
  Recording exported_before;
  CalibrationRecord old;
  {
    const SessionReader before(path);
    raw_before = before.read("angle");
    physical_before = before.physical("angle", raw_before);
    exported_before = session_to_recording(before);
    old = before.calibrations()[1];
  }
  REQUIRE(old.sensor_kind == "inclinometer");

  CalibrationRecord r = old;
  r.id = "inclinometer-SIM-INC10-0001-v1";
  r.coefficients = {0.001, old.coefficients[1] * 1.01};
  r.delay_s = 0.02;
  CHECK(apply_calibration(path, "angle", r) == old.id);
  {
    const SessionReader after(path);
    const ChannelSlice raw_after = after.read("angle");
    CHECK(raw_after.raw == raw_before.raw);
    CHECK(after.channel("angle").calibration_id == r.id);
    CHECK(after.calibrations().size() == 4);  // the old one stays
    const std::vector<double> physical_after = after.physical("angle", raw_after);
    CHECK_THAT(physical_after[100], Catch::WithinAbs(0.001 + 1.01 * physical_before[100], 1e-12));
    const SessionEvent last = after.events().back();
    CHECK(last.kind == "calibration");
    CHECK(last.channel == "angle");
    CHECK(last.detail == "applied inclinometer-SIM-INC10-0001-v1 (was " + old.id + ")");
    // Read through the export (as analysis reads), the angle is advanced by the delay.
    const Recording exported = session_to_recording(after);
    REQUIRE(exported.extra_names[0] == "inclinometer_angle_rad");
    CHECK_THAT(exported.extra_columns[0][1000], Catch::WithinAbs(physical_after[1020], 1e-9));
  }
  // Applying the old record again undoes it; a unit mismatch is refused.
  apply_calibration(path, "angle", old);
  CHECK(session_to_recording(SessionReader(path)).extra_columns[0] ==
        exported_before.extra_columns[0]);
  CalibrationRecord wrong = r;
  wrong.id = "wrong";
  wrong.unit = "N";
  CHECK_THROWS_WITH(apply_calibration(path, "angle", wrong),
                    path.string() +
                        ": channel angle has unit \"rad\" but calibration record "
                        "wrong gives \"N\"");
  CalibrationRecord clash = r;
  clash.coefficients[0] = 0.002;
  CHECK_THROWS_WITH(apply_calibration(path, "angle", clash),
                    Catch::EndsWith("already holds a different calibration record "
                                    "inclinometer-SIM-INC10-0001-v1 (records are never changed: "
                                    "make a new version)"));
}

TEST_CASE("Certificate: the table, the residual plot and the uncertainty",
          "[calibration][certificate]") {
  const std::string html = certificate_html(full_record());
  CHECK_THAT(html, Catch::Contains("<h1>Calibration certificate</h1>"));
  CHECK_THAT(html, Catch::Contains("load_cell-LC-7-v2"));
  CHECK_THAT(html, Catch::Contains("<svg"));
  CHECK_THAT(html, Catch::Contains("Reference points"));
  CHECK_THAT(html, Catch::Contains("Standard uncertainty of a calibrated value: <b>0.07 N</b>"));
  CHECK_THAT(html, Catch::Contains("supersedes load_cell-LC-7-v1"));
}

TEST_CASE("CLI: calibrate loadcell through its prompts, then calibration show and apply",
          "[calibration][cli]") {
  testing::TempDir dir("calibration_cli");
  const std::string exe = DOORBENCH_EXECUTABLE;
  const std::string store = (dir / "store").string();
  auto run = [&](const std::string& args, const std::string& input = "") {
    const std::string command = "cd '" + dir.path.string() + "' && printf '" + input + "' | '" +
                                exe + "' " + args + " > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    return std::make_tuple(WEXITSTATUS(status), read_file(dir / "out.txt"),
                           read_file(dir / "err.txt"));
  };
  // Five masses: 11 points, 11 Enters.
  auto [code, out, err] =
      run("calibrate loadcell --calibrations store --operator Ann "
          "--window-s 0.2 --certificate cert.html",
          "\\n\\n\\n\\n\\n\\n\\n\\n\\n\\n\\n");
  INFO(err);
  REQUIRE(code == 0);
  CHECK_THAT(err, Catch::Contains("[1/11] remove every load from the cell, then press Enter"));
  CHECK_THAT(err, Catch::Contains("stored load_cell-SIM-LC445-0001-v1 in"));
  CHECK(std::filesystem::exists(dir / "store" / "load_cell-SIM-LC445-0001-v1.json"));
  CHECK_THAT(read_file(dir / "cert.html"), Catch::Contains("<svg"));
  // The certificate's residual plot is XML, from calibrate and from calibration certificate.
  std::tie(code, out, err) = run(
      "calibration certificate load_cell-SIM-LC445-0001-v1 --calibrations store --out cert2.html");
  CHECK(code == 0);
  const testing::SvgCheck svgs = testing::check_svgs({dir / "cert.html", dir / "cert2.html"});
  INFO(svgs.output);
  CHECK(svgs.status == 0);
  CHECK(svgs.svgs == 2);
  // Input ends early: a clear message and exit status 1.
  std::tie(code, out, err) =
      run("calibrate loadcell --calibrations store --window-s 0.2", "\\n\\n");
  CHECK(code == 1);
  CHECK_THAT(err, Catch::Contains(
                      "calibration aborted at point 3 of 11 (10 kg, loading): the input ended"));

  testing::record_built_in_session(dir / "s.h5", 19.0, 4);
  std::tie(code, out, err) = run("calibrate gyro --from s.h5 --calibrations store --apply");
  INFO(err);
  CHECK(code == 0);
  CHECK_THAT(err, Catch::Contains("applied gyroscope-SIM-GYR100-0001-v1 to channel rate"));
  std::tie(code, out, err) = run("calibrate timing --from s.h5 --calibrations store");
  CHECK(code == 0);
  CHECK_THAT(err, Catch::Contains("timing: inclinometer against the integrated gyroscope on "));
  std::tie(code, out, err) =
      run("calibration apply s.h5 --record inclinometer-SIM-INC10-0001-v1 --calibrations store");
  CHECK(code == 0);
  CHECK_THAT(out, Catch::Contains("channel angle now uses inclinometer-SIM-INC10-0001-v1 (was "
                                  "nominal-SIM-INC10-0001); raw samples unchanged"));
  std::tie(code, out, err) = run("calibration show s.h5");
  CHECK(code == 0);
  CHECK_THAT(out, Catch::Contains("warning: inclinometer angle left its ±10° range "));
  CHECK_THAT(out, Catch::Contains("delay       15."));
  std::tie(code, out, err) = run("calibration show --calibrations store");
  CHECK_THAT(out, Catch::Contains(": 3 records"));
  std::tie(code, out, err) = run("calibration show nope --calibrations store");
  CHECK(code == 1);
  CHECK_THAT(err, Catch::Contains("no calibration record nope in store (3 records: "));
}
