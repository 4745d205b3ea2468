// The simulated bench recorded through the real session writer: its signals, passed back
// through the ideal inverse sensor models (the nominal calibration records), must match
// the simulator's truth within each sensor's noise; the same seed gives the same session.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <numeric>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/session_csv.h"
#include "core/units.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "simulated_bench/simulated_bench.h"

namespace {

using namespace doorbench;

// A file in this process's scratch folder (removed when the process ends).
std::filesystem::path fresh_path(const std::string& name) {
  static const doorbench::testing::TempDir scratch("simulated_bench");
  // Catch2 runs a test case again for each SECTION in the same process: start afresh.
  std::filesystem::remove(scratch / name);
  return scratch / name;
}

RigDefinition built_in_rig() {
  return parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
}

// Records `duration_s` of the built-in rig with `seed`; returns the session's path.
std::filesystem::path record(const std::string& name, double duration_s, std::uint64_t seed) {
  const auto path = fresh_path(name);
  const std::size_t scans = doorbench::testing::record_built_in_session(path, duration_s, seed);
  REQUIRE(scans == static_cast<std::size_t>(std::llround(duration_s * 1000.0)));
  return path;
}

struct Stats {
  double mean = 0, stddev = 0;
  std::size_t n = 0;
};

Stats stats(const std::vector<double>& values) {
  Stats s;
  s.n = values.size();
  if (s.n == 0) return s;
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / s.n;
  double sq = 0;
  for (double v : values) sq += (v - s.mean) * (v - s.mean);
  s.stddev = std::sqrt(sq / s.n);
  return s;
}

}  // namespace

TEST_CASE("Simulated bench: signals through the nominal calibration match the truth",
          "[simulated_bench][session]") {
  const auto path = record("one-cycle.h5", 6.0, 7);
  const SessionReader session(path);
  REQUIRE(session.channels().size() == 3);
  const std::vector<double> truth_theta = session.read_group_dataset("truth", "theta_rad");
  const std::vector<double> truth_omega = session.read_group_dataset("truth", "omega_rad_s");
  const std::vector<double> truth_force = session.read_group_dataset("truth", "force_N");
  REQUIRE(truth_theta.size() == 6000);

  // The door really opened (to the hand's 80°) and closed again.
  const double widest = *std::max_element(truth_theta.begin(), truth_theta.end());
  CHECK(widest > 75 * kRadPerDeg);
  CHECK(std::abs(truth_theta.back()) < 0.5 * kRadPerDeg);

  SECTION("gyroscope: the bias plus white noise") {
    const std::vector<double> rate = session.physical("rate", session.read("rate"));
    std::vector<double> error;
    // The door falls open by its weight faster than the gyroscope's ±100 °/s: leave out
    // the clipped samples.
    for (std::size_t i = 0; i < rate.size(); ++i) {
      if (std::abs(truth_omega[i]) < 95 * kRadPerDeg)
        error.push_back((rate[i] - truth_omega[i]) / kRadPerDeg);
    }
    const Stats s = stats(error);
    INFO("rate error: mean " << s.mean << " deg/s, std " << s.stddev << " deg/s");
    CHECK(std::abs(s.mean - 0.2) < 0.05);  // the reference gyro's 0.2 °/s bias
    CHECK(s.stddev > 0.04);                // 0.05 °/s noise, plus quantization
    CHECK(s.stddev < 0.07);
  }
  SECTION("inclinometer: where the door is still and inside the ±10° range") {
    const std::vector<double> angle = session.physical("angle", session.read("angle"));
    std::vector<double> error;
    for (std::size_t i = 200; i < angle.size(); ++i) {
      const bool still = std::abs(truth_omega[i]) < 1e-3 && std::abs(truth_omega[i - 200]) < 1e-3;
      if (still && std::abs(truth_theta[i]) < 9 * kRadPerDeg) {
        error.push_back((angle[i] - truth_theta[i]) / kRadPerDeg);
      }
    }
    const Stats s = stats(error);
    INFO(s.n << " still samples: mean " << s.mean << " deg, std " << s.stddev << " deg");
    REQUIRE(s.n > 500);
    CHECK(std::abs(s.mean) < 0.005);
    CHECK(s.stddev < 0.02);  // 0.01° noise plus quantization
    // Beyond its range the inclinometer saturates at 10°.
    const double largest = *std::max_element(angle.begin(), angle.end());
    CHECK(largest == Approx(10 * kRadPerDeg).epsilon(0.002));
  }
  SECTION("load cell: the hand's force, signed by the stroke's mounting") {
    const Recording exported = session_to_recording(session);
    REQUIRE(exported.stroke.has_value());
    std::vector<double> error;
    for (std::size_t i = 0; i < exported.size(); ++i) {
      // Only where the hand presses on the cell by more than 1 N (a compression-only cell
      // reads 0 else). Strokes alternate from an opening: odd ids open, even ids close.
      const int stroke = (*exported.stroke)[i];
      const double mounting = stroke % 2 == 1 ? 1.0 : -1.0;
      if (stroke != 0 && truth_force[i] * mounting > 1.0) {
        error.push_back(exported.force_N[i] - truth_force[i]);
      }
    }
    const Stats s = stats(error);
    INFO(s.n << " pressed samples: mean " << s.mean << " N, std " << s.stddev << " N");
    REQUIRE(s.n > 1000);
    CHECK(std::abs(s.mean) < 0.3);  // non-linearity and hysteresis, each ~0.1-0.2 N
    CHECK(s.stddev > 0.15);         // the 0.2 N noise is there
    CHECK(s.stddev < 0.4);
    // The load cell cannot read a pull: in an opening stroke it never reads below 0 N
    // beyond its noise.
    for (std::size_t i = 0; i < exported.size(); ++i) {
      if ((*exported.stroke)[i] == 1) CHECK(exported.force_N[i] > -1.5);
    }
  }
}

TEST_CASE("Simulated bench: strokes and the trigger are recorded as events",
          "[simulated_bench][session]") {
  const auto path = record("two-cycles.h5", 12.0, 3);
  const SessionReader session(path);
  int triggers = 0, openings = 0, closings = 0, ends = 0;
  for (const SessionEvent& event : session.events()) {
    triggers += event.kind == "trigger";
    openings += event.kind == "stroke_start" && event.detail == "opening";
    closings += event.kind == "stroke_start" && event.detail == "closing";
    ends += event.kind == "stroke_end";
  }
  CHECK(triggers == 1);
  CHECK(openings == 2);
  CHECK(closings == 2);
  CHECK(ends == 4);
  CHECK(session.calibrations().size() == 3);
  CHECK(session.metadata().rig_name == "simulated-dishwasher");
}

TEST_CASE("Simulated bench: the seed makes the session repeatable", "[simulated_bench][session]") {
  const SessionReader a(record("seed-a.h5", 1.0, 11));
  const SessionReader b(record("seed-b.h5", 1.0, 11));
  const SessionReader c(record("seed-c.h5", 1.0, 12));
  for (const std::string channel : {"force", "angle", "rate"}) {
    INFO(channel);
    CHECK(a.read(channel).raw == b.read(channel).raw);
    CHECK(a.read(channel).raw != c.read(channel).raw);
  }
}

#include <fstream>

#include "analysis/model/parameter_file.h"
#include "analysis/simulation/trajectory_io.h"
#include "analysis/simulation/virtual_hand.h"
#include "tests/support/allocation_counter.h"

namespace {

// The built-in rig with its [simulation.hand] table replaced by `force = "force.csv"`.
std::string scripted_rig_text() {
  std::string text(simulated_dishwasher_rig_text());
  const auto hand = text.find("[simulation.hand]");
  REQUIRE(hand != std::string::npos);
  text = text.substr(0, hand);
  const auto simulation = text.find("[simulation]");
  text.insert(text.find('\n', simulation) + 1, "force = \"force.csv\"\n");
  return text;
}

}  // namespace

TEST_CASE("Simulated bench: a scripted force drives the door, its strokes mount the load cell",
          "[simulated_bench][session]") {
  // The script: the virtual hand's force from a plain simulation, strokes 1 and 2.
  const DoorModel door = reference_model(ModelKind::kPhysical);
  VirtualHandOptions hand_options;
  hand_options.duration_s = 4.0;
  const VirtualHand hand(hand_options, door.geometry().handle_radius_m);
  std::vector<double> times(4001);
  for (std::size_t i = 0; i < times.size(); ++i) times[i] = i * 1e-3;
  Trajectory run = simulate(door, hand, DoorState{}, times);
  for (double t : times) run.stroke.push_back(hand.stroke_at(t));
  const doorbench::testing::TempDir scratch("scripted_force");
  const std::filesystem::path dir = scratch.path;
  write_recording_csv_file(dir / "force.csv", to_recording(run, "test script"));

  const RigDefinition rig = parse_rig(scripted_rig_text(), "scripted.toml", dir);
  REQUIRE(rig.simulation->force == "force.csv");
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  const auto script = simulated_bench::simulated_hand(rig, model);
  CHECK(script->natural_duration_s() == 4.0);
  simulated_bench::SimulatedBench bench(rig, model, 4.0);
  RecordOptions options;
  options.duration_s = 4.0;
  const auto path = dir / "scripted.h5";
  record_session(bench, SessionMetadata{}, path, options);

  const SessionReader session(path);
  std::vector<std::string> starts;
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "stroke_start") starts.push_back(event.detail);
  }
  CHECK(starts == std::vector<std::string>{"opening", "closing"});
  // The truth's force is the script's, sample for sample.
  const std::vector<double> truth_force = session.read_group_dataset("truth", "force_N");
  REQUIRE(truth_force.size() == 4000);
  for (std::size_t i = 0; i < truth_force.size(); i += 97) {
    CHECK(truth_force[i] == Approx(run.force_N[i]).margin(1e-9));
  }
  // The same force replayed gives the same door (the bench's stepper matches simulate()).
  const std::vector<double> theta = session.read_group_dataset("truth", "theta_rad");
  CHECK(*std::max_element(theta.begin(), theta.end()) > 1.2);
}

TEST_CASE("Simulated bench: reading scans allocates nothing once started",
          "[simulated_bench][allocation]") {
  const RigDefinition rig = built_in_rig();
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  simulated_bench::SimulatedBench bench(rig, model, 18.0);
  ScanBlock block(bench.channels().size(), 100);
  bench.start();
  block.events.clear();
  bench.read(block);  // the first block, with the start trigger
  const long long before = doorbench::testing::allocations();
  for (int i = 0; i < 170; ++i) {  // 17 s: every stroke of the three cycles
    block.events.clear();
    REQUIRE(bench.read(block) == 100);
  }
  CHECK(doorbench::testing::allocations() - before == 0);
}

// Only a lower bound: a slow machine makes this longer, never shorter, so the check does
// not depend on how busy the machine is.
TEST_CASE("Simulated bench: realtime = true paces the scans in real time", "[simulated_bench]") {
  RigDefinition rig = built_in_rig();
  rig.simulation->realtime = true;
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  simulated_bench::SimulatedBench bench(rig, model, 0.3);
  ScanBlock block(bench.channels().size(), 100);
  const auto started = std::chrono::steady_clock::now();
  bench.start();
  for (int i = 0; i < 3; ++i) bench.read(block);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  CHECK(elapsed_s >= 0.3);
}
