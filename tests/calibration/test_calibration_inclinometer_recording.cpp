// The inclinometer calibrated from a recording of reference angles held in order: on
// simulated recordings with known truth (offset, gain error, noise, the sensor's lag), the
// holds are found, matched and fitted, and the recovered offset and gain lie within 2u;
// recordings whose holds do not match the references get clear messages; the command line
// stores and applies the record.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <tuple>

#include "acquisition/rig/rig_file.h"
#include "calibration/inclinometer_calibration.h"
#include "calibration/static_source.h"
#include "core/units.h"
#include "fixtures/temp_dir.h"
#include "sensors/rig_channel.h"
#include "simulated_bench/simulated_bench.h"
#include "tests/support/files.h"

using doorbench::testing::read_file;

using namespace doorbench;
using namespace doorbench::calibration;

namespace {

struct Truth {
  double offset_deg = 0.4;
  double output_V_per_deg = 0.404;  // 1 % above the datasheet's 0.4 V/°
  double noise_deg = 0.02;
};

// The angle (°) of a recording that holds each of `holds_deg` for hold_s, moving between
// them in move_s (a smooth cosine step).
double held_angle_deg(const std::vector<double>& holds_deg, double hold_s, double move_s,
                      double t) {
  const double period = hold_s + move_s;
  const auto k = static_cast<std::size_t>(std::max(0.0, std::floor(t / period)));
  if (k + 1 >= holds_deg.size()) return holds_deg.back();
  const double into = t - k * period;
  if (into <= hold_s) return holds_deg[k];
  const double s = (into - hold_s) / move_s;
  return holds_deg[k] +
         (holds_deg[k + 1] - holds_deg[k]) * (1 - std::cos(std::numbers::pi * s)) / 2;
}

// A session of the built-in rig's inclinometer (its nominal record, the datasheet's) whose
// sensor has the truth's offset, gain and noise, recorded at 1 kHz through the rig's DAQ.
void write_hold_recording(const std::filesystem::path& path, const std::vector<double>& holds_deg,
                          std::uint64_t seed, const Truth& truth = {}, double hold_s = 3.0,
                          double move_s = 1.5) {
  const RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  const RigChannel& channel = *rig.find_channel("angle");
  doorbench::InclinometerParameters p = inclinometer_parameters(channel);
  p.offset_deg = truth.offset_deg;
  p.output_V_per_deg = truth.output_V_per_deg;
  p.noise_rms_deg = truth.noise_deg;
  sensors::Inclinometer sensor(p, 1000.0, seed);
  sensor.settle(holds_deg.front() / kDegPerRad);
  const sensors::Daq daq{doorbench::DaqParameters{}};
  SessionMetadata metadata;
  metadata.rig_name = rig.name;
  metadata.rig_definition = rig.text;
  SessionWriter writer(path, metadata);
  const CalibrationRecord record = sensors::nominal_calibration(channel);
  writer.add_calibration(record);
  ChannelInfo info;
  info.name = channel.name;
  info.sensor_kind = channel.sensor;
  info.sensor_serial = channel.serial;
  info.raw_offset = -10.0;
  info.raw_scale = daq.volts_per_count();
  info.unit = channel.unit;
  info.calibration_id = record.id;
  const int index = writer.add_channel(info);
  const double duration_s = holds_deg.size() * (hold_s + move_s) - move_s;
  const auto n = static_cast<std::size_t>(duration_s * 1000.0);
  std::vector<std::int32_t> counts(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / 1000.0;
    counts[i] =
        daq.to_counts(sensor.sample_V(held_angle_deg(holds_deg, hold_s, move_s, t) / kDegPerRad));
  }
  writer.append_counts(index, counts);
  writer.close();
}

InclinometerCalibrationOptions datasheet_options() {
  InclinometerCalibrationOptions options;
  options.range_deg = 10.0;
  options.output_V_per_deg = 0.4;
  return options;
}

}  // namespace

TEST_CASE("Inclinometer from a recording: holds found, offset and gain within 2u",
          "[calibration][inclinometer]") {
  testing::TempDir dir("calibration_inclinometer_recording");
  const std::vector<double> angles{-8, -4, 0, 4, 8};
  const Truth truth;
  const double true_gain = 1.0 / (truth.output_V_per_deg * kDegPerRad);
  int offset_inside = 0, gain_inside = 0;
  const int seeds = 100;
  for (int seed = 1; seed <= seeds; ++seed) {
    const auto path = dir / std::to_string(seed).append(".h5");
    write_hold_recording(path, angles, seed);
    const SessionReader session(path);
    const InclinometerRecordingPoints holds =
        inclinometer_points_from_recording(session, "", angles);
    REQUIRE(holds.holds.size() == 5);
    const InclinometerCalibration result =
        calibrate_inclinometer(holds.points(), datasheet_options(), {});
    offset_inside += std::abs(result.offset_deg - truth.offset_deg) <= 2 * result.offset_std_deg;
    gain_inside += std::abs(result.gain_rad_per_V - true_gain) <= 2 * result.gain_std_rad_per_V;
    if (seed == 1) {
      INFO(holds.brief_report() << result.brief_report());
      // Each 3 s hold less the stillness window's half (0.25 s) and the guards (0.2 s) at
      // both ends; the noise estimated from the second differences.
      for (std::size_t k = 0; k < 5; ++k) {
        const InclinometerHold& h = holds.holds[k];
        CHECK(h.point.reference == angles[k] / kDegPerRad);
        CHECK(h.samples > 1800);
        CHECK_THAT(h.mean_deg, Catch::WithinAbs(1.01 * (angles[k] + truth.offset_deg), 0.01));
      }
      CHECK_THAT(holds.noise_deg, Catch::WithinRel(truth.noise_deg, 0.1));
      CHECK_THAT(result.offset_deg, Catch::WithinAbs(truth.offset_deg, 0.002));
      CHECK_THAT(result.gain_rad_per_V, Catch::WithinRel(true_gain, 1e-3));
    }
  }
  INFO("offset " << offset_inside << ", gain " << gain_inside << " of " << seeds << " inside 2u");
  CHECK(offset_inside >= 90);
  CHECK(gain_inside >= 90);
}

TEST_CASE("Inclinometer from a recording: holds that do not match the references",
          "[calibration][inclinometer]") {
  testing::TempDir dir("calibration_inclinometer_recording_bad");
  const auto path = dir / "five.h5";
  write_hold_recording(path, {-8, -4, 0, 4, 8}, 7);
  const SessionReader session(path);
  const std::vector<double> four{-8, -4, 0, 4};
  CHECK_THROWS_WITH(
      inclinometer_points_from_recording(session, "", four),
      Catch::StartsWith(path.string() +
                        ": found 5 still windows in inclinometer angle where 4 reference angles "
                        "were given (-8,-4,0,4°): 0.") &&
          Catch::Contains(" s reads -7.68°; ") && Catch::Contains("hold each reference once"));
  const std::vector<double> shuffled{-8, 0, -4, 4, 8};
  CHECK_THROWS_WITH(inclinometer_points_from_recording(session, "", shuffled),
                    Catch::Contains("the holds do not follow the reference angles (-8,0,-4,4,8°) "
                                    "in order: from 0° to -4° the reading went from -3.64° to "
                                    "0.40°"));
  // Holds too short for the stillness test: none found.
  const auto brisk = dir / "brisk.h5";
  write_hold_recording(brisk, {-8, -4, 0, 4, 8}, 8, Truth{}, 1.0, 1.0);
  CHECK_THROWS_WITH(inclinometer_points_from_recording(SessionReader(brisk), "", four),
                    Catch::Contains("found 0 still windows") && Catch::Contains(": none. "));
}

TEST_CASE("CLI: calibrate inclinometer --from a recording, stored and applied",
          "[calibration][inclinometer][cli]") {
  testing::TempDir dir("calibration_inclinometer_cli");
  write_hold_recording(dir / "holds.h5", {-8, -4, 0, 4, 8}, 11);
  const std::string exe = DOORBENCH_EXECUTABLE;
  auto run = [&](const std::string& args) {
    const std::string command = "cd '" + dir.path.string() + "' && '" + exe + "' " + args +
                                " < /dev/null > out.txt 2> err.txt";
    const int status = std::system(command.c_str());
    return std::make_tuple(WEXITSTATUS(status), read_file(dir / "out.txt"),
                           read_file(dir / "err.txt"));
  };
  auto [code, out, err] =
      run("calibrate inclinometer --from holds.h5 --angles-deg -8,-4,0,4,8 --calibrations store "
          "--apply");
  INFO(err);
  REQUIRE(code == 0);
  CHECK_THAT(err, Catch::Contains("inclinometer holds found in the recording"));
  CHECK_THAT(err, Catch::Contains("offset 0.399"));
  CHECK_THAT(err, Catch::Contains("applied inclinometer-SIM-INC10-0001-v1 to channel angle"));
  CHECK_THAT(out, Catch::Contains("\"supersedes\": \"nominal-SIM-INC10-0001\""));
  std::tie(code, out, err) =
      run("calibrate inclinometer --from holds.h5 --angles-deg -8,-4,0,4 --calibrations store");
  CHECK(code == 1);
  CHECK_THAT(err, Catch::Contains("found 5 still windows in inclinometer angle where 4 "));
}
