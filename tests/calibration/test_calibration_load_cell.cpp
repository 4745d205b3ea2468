// Load-cell and inclinometer calibration through the guided procedure on simulated
// sensors with known truth: recovered gain and offset lie within their reported
// uncertainty (±2u for at least 90 of 100 seeds); the prompts, the tare and the messages
// for bad procedures.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <sstream>

#include "acquisition/rig/rig_file.h"
#include "calibration/guided_procedure.h"
#include "calibration/inclinometer_calibration.h"
#include "calibration/load_cell_calibration.h"
#include "calibration/static_source.h"
#include "core/units.h"

using namespace doorbench;
using namespace doorbench::calibration;

namespace {

// The built-in rig with some of a channel's parameters changed.
RigDefinition rig_with(const std::string& channel,
                       const std::vector<std::pair<std::string, double>>& changes) {
  RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  for (RigChannel& c : rig.channels) {
    if (c.name != channel) continue;
    for (const auto& [name, value] : changes) {
      bool found = false;
      for (auto& [known, old] : c.parameters) {
        if (known == name) {
          old = value;
          found = true;
        }
      }
      if (!found) c.parameters.emplace_back(name, value);
    }
  }
  return rig;
}

GuidedOptions load_cell_guided(double gain_N_per_V) {
  GuidedOptions g;
  g.max_std_V = 1.0 / gain_N_per_V;
  g.max_drift_V = 0.3 / gain_N_per_V;
  g.display_per_V = gain_N_per_V;
  g.display_unit = "N";
  return g;
}

std::vector<CalibrationPoint> run_quietly(StaticSignalSource& source,
                                          const std::vector<GuidedPoint>& plan,
                                          const GuidedOptions& options) {
  std::istringstream in(std::string(plan.size(), '\n'));
  std::ostringstream out;
  return run_guided_points(source, plan, options, in, out);
}

// A source whose reading keeps creeping (a load still swinging, a creeping cell).
class CreepingSource final : public StaticSignalSource {
 public:
  std::string description() const override { return "creeping test source"; }
  double sample_rate_hz() const override { return 1000.0; }
  void expect_reference(double) override {}
  std::vector<double> read_V(std::size_t samples) override {
    std::vector<double> v(samples);
    for (double& x : v) x = 1.0 + 1e-4 * static_cast<double>(count_++);
    return v;
  }

 private:
  std::size_t count_ = 0;
};

}  // namespace

TEST_CASE("Load cell: gain and offset within 2u for at least 90 of 100 seeds",
          "[calibration][load_cell]") {
  // Noise only (no bow, no hysteresis): the straight line is then the truth.
  const RigDefinition rig = rig_with("force", {{"nonlinearity_fraction_fs", 0.0},
                                               {"hysteresis_fraction_fs", 0.0},
                                               {"zero_offset_N", 1.7},
                                               {"noise_rms_N", 0.5}});
  const RigChannel& channel = *rig.find_channel("force");
  const auto p = load_cell_parameters(channel);
  const double true_gain = 1.0 / p.volts_per_newton();
  const double true_offset = -p.zero_offset_N;
  const std::vector<double> masses{5, 10, 20, 30, 40};
  const auto plan = load_cell_mass_points(masses);
  GuidedOptions guided = load_cell_guided(true_gain);
  guided.window_s = 0.2;
  int gain_inside = 0, offset_inside = 0, quadratic = 0;
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    SimulatedStaticSource source(rig, channel, seed);
    const auto points = run_quietly(source, plan, guided);
    const LoadCellCalibration r = calibrate_load_cell(points, {}, {});
    gain_inside += std::abs(r.gain_N_per_V - true_gain) <= 2 * r.gain_std_N_per_V;
    offset_inside += std::abs(r.offset_N - true_offset) <= 2 * r.offset_std_N;
    quadratic += r.quadratic;
  }
  INFO("gain " << gain_inside << ", offset " << offset_inside << " of 100; quadratic "
               << quadratic);
  CHECK(gain_inside >= 90);
  CHECK(offset_inside >= 90);
  CHECK(quadratic <= 5);  // a quadratic term only where it is significant
}

TEST_CASE("Load cell: non-linearity and hysteresis in % of full scale",
          "[calibration][load_cell]") {
  const RigDefinition rig = rig_with("force", {{"noise_rms_N", 0.05}});
  const RigChannel& channel = *rig.find_channel("force");
  SimulatedStaticSource source(rig, channel, 5);
  const std::vector<double> masses{5, 10, 15, 20, 25, 30, 35, 40, 45};
  const auto points = run_quietly(source, load_cell_mass_points(masses), load_cell_guided(44.5));
  const LoadCellCalibration r =
      calibrate_load_cell(points, {}, RecordHeader{.sensor_serial = "LC-1"});
  // The model's hysteresis is 0.03 % FS; its bow (0.05 % FS at mid-scale) is significant.
  CHECK_THAT(r.hysteresis_percent_fs, Catch::WithinAbs(0.03, 0.005));
  CHECK(r.quadratic);
  CHECK(r.nonlinearity_percent_fs > 0.01);
  CHECK(r.nonlinearity_percent_fs < 0.06);
  CHECK(r.record.points.size() == 19);
  CHECK(r.record.id == "load_cell-LC-1-v1");
  CHECK(r.record.quantity("hysteresis_percent_fs")->value == r.hysteresis_percent_fs);
  CHECK(r.brief_report().find("hysteresis") != std::string::npos);
}

TEST_CASE("Load cell: the guided procedure is driven through its prompts",
          "[calibration][load_cell][guided]") {
  const RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  SimulatedStaticSource source(rig, *rig.find_channel("force"), 3);
  const std::vector<double> masses{10, 20};
  const auto plan = load_cell_mass_points(masses);
  REQUIRE(plan.size() == 5);  // 0, 10, 20 loading; 10, 0 unloading
  std::istringstream in("\n\n\n\n\n");
  std::ostringstream out;
  const auto points = run_guided_points(source, plan, load_cell_guided(44.5), in, out);
  const std::string dialogue = out.str();
  CHECK_THAT(
      dialogue,
      Catch::Contains("[1/5] remove every load from the cell, then press Enter (q to quit): "));
  CHECK_THAT(dialogue, Catch::Contains("[3/5] load the cell with 20 kg in all, then press Enter"));
  CHECK_THAT(dialogue, Catch::Contains("[4/5] unload the cell to 10 kg in all, then press Enter"));
  CHECK_THAT(dialogue, Catch::Contains(" V, sd ") && Catch::Contains(" N) over 1000 samples"));
  REQUIRE(points.size() == 5);
  CHECK(points[3].branch == "unloading");
  CHECK_THAT(points[2].signal, Catch::WithinAbs(20 * 9.80665 / 44.5, 0.01));

  // q aborts, and so does the end of the input.
  std::istringstream quit("\nq\n");
  CHECK_THROWS_WITH(run_guided_points(source, plan, load_cell_guided(44.5), quit, out),
                    "calibration aborted by the operator at point 2 of 5 (10 kg, loading)");
  std::istringstream ended("\n");
  CHECK_THROWS_WITH(run_guided_points(source, plan, load_cell_guided(44.5), ended, out),
                    "calibration aborted at point 2 of 5 (10 kg, loading): the input ended");
}

TEST_CASE("Load cell: unstable readings, too few points, references out of range",
          "[calibration][load_cell]") {
  CreepingSource creeping;
  const std::vector<double> masses{10};
  std::istringstream in("\n");
  std::ostringstream out;
  GuidedOptions options = load_cell_guided(44.5);
  options.max_windows = 3;
  CHECK_THROWS_WITH(
      run_guided_points(creeping, load_cell_mass_points(masses), options, in, out),
      Catch::StartsWith("the reading did not settle at point 1 of 3 (0 kg, loading): in each of 3 "
                        "windows of 1 s the standard deviation or drift was above its limit") &&
          Catch::EndsWith("steady the reference (no swinging load, no touching) and repeat"));
  CHECK_THAT(out.str(), Catch::Contains("not yet stable (window 1/3"));

  auto point = [](double reference_N, double signal_V) {
    CalibrationPoint p;
    p.reference = reference_N;
    p.signal = signal_V;
    return p;
  };
  const std::vector<CalibrationPoint> three{point(0, 0), point(100, 2.25), point(200, 4.5)};
  CHECK_THROWS_WITH(calibrate_load_cell(three, {}, {}),
                    "load-cell calibration: 3 different references (3 points); at least 5 are "
                    "needed, spread from 0 to full scale (445 N)");
  std::vector<CalibrationPoint> over{point(0, 0), point(100, 2.25), point(200, 4.5),
                                     point(300, 6.7), point(500, 11.2)};
  CHECK_THROWS_WITH(calibrate_load_cell(over, {}, {}),
                    "load-cell calibration: reference 500 N (50.99 kg) is above the cell's full "
                    "scale 445 N; use references from 0 to full scale");
  over.back() = point(-20, -0.4);
  CHECK_THROWS_WITH(calibrate_load_cell(over, {}, {}),
                    "load-cell calibration: reference -20 N is negative, but the cell reads "
                    "compression only; use references from 0 to full scale");
  const std::vector<CalibrationPoint> narrow{point(0, 0), point(10, 0.22), point(20, 0.45),
                                             point(30, 0.67), point(40, 0.9)};
  CHECK_THROWS_WITH(calibrate_load_cell(narrow, {}, {}),
                    Catch::StartsWith("load-cell calibration: the references span 40 N, less "
                                      "than 20 % of full scale (445 N)"));
  LoadCellCalibrationOptions bad;
  bad.full_scale_N = 0;
  CHECK(bad.validate() == "load-cell calibration full_scale_N = 0 must be > 0");
}

TEST_CASE("Load cell: the tare makes the unloaded cell read zero", "[calibration][load_cell]") {
  const RigDefinition rig = rig_with("force", {{"zero_offset_N", 3.0}});
  const RigChannel& channel = *rig.find_channel("force");
  SimulatedStaticSource source(rig, channel, 9);
  const std::vector<double> masses{5, 10, 20, 30, 40};
  const auto points = run_quietly(source, load_cell_mass_points(masses), load_cell_guided(44.5));
  const LoadCellCalibration calibrated =
      calibrate_load_cell(points, {}, RecordHeader{.sensor_serial = "S1"});
  // Later the zero has moved by another 1 N: the unloaded cell reads +1 N.
  const double unloaded_V = (3.0 + 1.0) / 44.5;
  RecordHeader header{.sensor_serial = "S1"};
  header.version = 2;
  const CalibrationRecord tared =
      tare_load_cell(calibrated.record, unloaded_V, 0.0045, 1000, header);
  CHECK_THAT(tared.apply(unloaded_V), Catch::WithinAbs(0.0, 1e-9));
  CHECK(tared.supersedes == calibrated.record.id);
  CHECK(tared.id == "load_cell-S1-v2");
  CHECK_THAT(tared.quantity("tare_reading_before_N")->value, Catch::WithinAbs(1.0, 0.1));
  CHECK(tared.coefficients[1] == calibrated.record.coefficients[1]);
}

TEST_CASE("Inclinometer: offset and gain within 2u for at least 90 of 100 seeds",
          "[calibration][inclinometer]") {
  const RigDefinition rig = rig_with("angle", {{"offset_deg", 0.35}, {"noise_rms_deg", 0.05}});
  const RigChannel& channel = *rig.find_channel("angle");
  const double true_gain = (1.0 / kDegPerRad) / 0.4;
  const std::vector<double> angles{-8, -4, 0, 4, 8};
  GuidedOptions guided;
  guided.window_s = 0.2;
  guided.max_std_V = 0.2 * 0.4;
  guided.max_drift_V = 0.05 * 0.4;
  guided.display_per_V = 2.5;
  guided.display_unit = "°";
  int gain_inside = 0, offset_inside = 0;
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    SimulatedStaticSource source(rig, channel, seed);
    const auto points = run_quietly(source, inclinometer_angle_points(angles), guided);
    const InclinometerCalibration r = calibrate_inclinometer(points, {}, {});
    gain_inside += std::abs(r.gain_rad_per_V - true_gain) <= 2 * r.gain_std_rad_per_V;
    offset_inside += std::abs(r.offset_deg - 0.35) <= 2 * r.offset_std_deg;
  }
  INFO("gain " << gain_inside << ", offset " << offset_inside << " of 100");
  CHECK(gain_inside >= 90);
  CHECK(offset_inside >= 90);
}

TEST_CASE("Inclinometer: references out of range and too few are refused",
          "[calibration][inclinometer]") {
  auto point = [](double deg, double signal_V) {
    CalibrationPoint p;
    p.reference = deg / kDegPerRad;
    p.signal = signal_V;
    return p;
  };
  const std::vector<CalibrationPoint> far{point(-5, -2), point(0, 0), point(9.5, 3.8)};
  CHECK_THROWS_WITH(calibrate_inclinometer(far, {}, {}),
                    "inclinometer calibration: reference angle 9.500° is outside ±9° (90 % of "
                    "the inclinometer's range ±10°); a saturated reading says nothing about the "
                    "gain");
  const std::vector<CalibrationPoint> saturated{point(-5, -2), point(0, 0), point(8.9, 4.0)};
  CHECK_THROWS_WITH(calibrate_inclinometer(saturated, {}, {}),
                    "inclinometer calibration: at reference 8.900° the reading 4.0000 V is at "
                    "the end of the range (saturated); use smaller angles");
  const std::vector<CalibrationPoint> two{point(-5, -2), point(5, 2), point(5, 2.001)};
  CHECK_THROWS_WITH(calibrate_inclinometer(two, {}, {}),
                    "inclinometer calibration: 2 different reference angles (3 points); at least "
                    "3 are needed across the range ±10°");
}
