// Preprocessing against the simulated bench's truth: sessions recorded with the real
// simulated bench (the reference door, its sensors and DAQ), exported with
// session_to_recording and prepared; the fused angle, the rate, the bias, the strokes and
// the noise levels are compared with the session's truth group. Also: a saturated gyroscope
// segment, a rate-only and an angle-only recording, a CSV of an exact simulator run, the
// zero-phase filter and the error messages.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/session_csv.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/simulation/trajectory_io.h"
#include "analysis/simulation/virtual_hand.h"
#include "core/units.h"
#include "fixtures/simulated_session.h"
#include "simulated_bench/simulated_bench.h"

namespace {

using namespace doorbench;

// CTest runs each test case as its own process, in parallel: one folder per process,
// removed when the process ends.
struct TestFolder {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("doorbench_test_preprocessing-" + std::to_string(::getpid()));
  ~TestFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

std::filesystem::path fresh_path(const std::string& name) {
  static const TestFolder folder;
  std::filesystem::create_directories(folder.path);
  const auto path = folder.path / name;
  std::filesystem::remove(path);
  return path;
}

// Three openings and closings of the reference door on the built-in simulated bench (18 s
// of the virtual hand, then rest), recorded through the real session writer. The sensory
// door stays inside every sensor's range (fixtures/simulated_session.h).
std::filesystem::path record(const std::string& name, double duration_s, std::uint64_t seed,
                             const std::string& model_kind = "sensory") {
  const auto path = fresh_path(name);
  doorbench::testing::record_built_in_session(path, duration_s, seed, model_kind);
  return path;
}

struct BenchSession {
  std::filesystem::path path;
  Recording recording;
  std::vector<double> truth_time, truth_theta, truth_omega, truth_force;
  std::vector<SessionEvent> starts;  // stroke_start events, in time order
  std::vector<double> ends_s;        // stroke_end times, in time order
};

// Recorded once for all the test cases below (about 0.3 s).
const BenchSession& bench_session() {
  static const BenchSession session = [] {
    BenchSession s;
    s.path = record("three-cycles.h5", 18.6, 11);
    const SessionReader reader(s.path);
    s.recording = session_to_recording(reader);
    s.truth_time = reader.read_group_dataset("truth", "time_s");
    s.truth_theta = reader.read_group_dataset("truth", "theta_rad");
    s.truth_omega = reader.read_group_dataset("truth", "omega_rad_s");
    s.truth_force = reader.read_group_dataset("truth", "force_N");
    for (const SessionEvent& event : reader.events()) {
      if (event.kind == "stroke_start") s.starts.push_back(event);
      if (event.kind == "stroke_end") s.ends_s.push_back(event.time_s);
    }
    return s;
  }();
  return session;
}

// The truth sample at a recording time (both on the 1 kHz scan clock).
std::size_t truth_index(const BenchSession& s, double time_s) {
  const auto i = static_cast<std::size_t>(std::llround(time_s * 1000.0));
  REQUIRE(i < s.truth_time.size());
  REQUIRE(std::abs(s.truth_time[i] - time_s) < 1e-9);
  return i;
}

struct Errors {
  double theta_rms = 0, theta_max = 0, omega_rms = 0;
  std::size_t n = 0;
};

Errors errors_against_truth(const BenchSession& s, const std::vector<Stroke>& strokes) {
  Errors e;
  double sq_theta = 0, sq_omega = 0;
  for (const Stroke& stroke : strokes) {
    for (std::size_t k = 0; k < stroke.size(); ++k) {
      const std::size_t i = truth_index(s, stroke.time_s[k]);
      const double d_theta = stroke.theta_rad[k] - s.truth_theta[i];
      const double d_omega = stroke.omega_rad_s[k] - s.truth_omega[i];
      sq_theta += d_theta * d_theta;
      sq_omega += d_omega * d_omega;
      e.theta_max = std::max(e.theta_max, std::abs(d_theta));
      ++e.n;
    }
  }
  e.theta_rms = std::sqrt(sq_theta / static_cast<double>(e.n));
  e.omega_rms = std::sqrt(sq_omega / static_cast<double>(e.n));
  return e;
}

Recording without_inclinometer(Recording recording) {
  recording.extra_names.clear();
  recording.extra_columns.clear();
  return recording;
}

// One open-close cycle of the virtual hand on the exact simulator (reference physical
// door), as a recording with its strokes: angle_rad and rate_rad_s are the exact truth.
Trajectory exact_run() {
  const DoorModel model = reference_model(ModelKind::kPhysical);
  VirtualHandOptions hand_options;
  hand_options.duration_s = 6.0;
  const VirtualHand hand(hand_options, model.geometry().handle_radius_m);
  std::vector<double> times(6001);
  for (std::size_t i = 0; i < times.size(); ++i) times[i] = static_cast<double>(i) / 1000.0;
  Trajectory run = simulate(model, hand, DoorState{}, times);
  run.stroke.resize(times.size());
  for (std::size_t i = 0; i < times.size(); ++i) run.stroke[i] = hand.stroke_at(times[i]);
  return run;
}

bool has_note(const PreparedData& data, const std::string& text) {
  for (const std::string& note : data.notes) {
    if (note.find(text) != std::string::npos) return true;
  }
  return false;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Removes rows [first, first + count) from every column.
void erase_rows(Recording& recording, std::size_t first, std::size_t count) {
  auto erase = [&](auto& column) {
    column.erase(column.begin() + static_cast<std::ptrdiff_t>(first),
                 column.begin() + static_cast<std::ptrdiff_t>(first + count));
  };
  erase(recording.time_s);
  erase(recording.force_N);
  if (recording.rate_rad_s) erase(*recording.rate_rad_s);
  if (recording.angle_rad) erase(*recording.angle_rad);
  if (recording.stroke) erase(*recording.stroke);
  for (auto& column : recording.extra_columns) erase(column);
}

std::size_t index_at(const Recording& recording, double time_s) {
  return static_cast<std::size_t>(
      std::lower_bound(recording.time_s.begin(), recording.time_s.end(), time_s - 1e-9) -
      recording.time_s.begin());
}

// A small in-memory recording: the door at rest, then moving at 10 °/s.
Recording synthetic(std::size_t n) {
  Recording recording;
  recording.source = "mem";
  for (std::size_t i = 0; i < n; ++i) {
    recording.time_s.push_back(static_cast<double>(i) / 1000.0);
    recording.force_N.push_back(0.0);
  }
  return recording;
}

std::string error_of(const Recording& recording, const PreprocessingOptions& options = {}) {
  try {
    prepare(recording, options);
  } catch (const PreprocessingError& error) {
    return error.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("Preprocessing: the fused angle, the rate and the bias match the bench's truth",
          "[preprocessing]") {
  const BenchSession& s = bench_session();
  REQUIRE(s.recording.stroke.has_value());
  REQUIRE_FALSE(s.recording.angle_rad.has_value());
  REQUIRE(s.recording.extra_names == std::vector<std::string>{"inclinometer_angle_rad"});
  const PreparedData data = prepare(s.recording);

  CHECK(data.source == s.path.string());
  CHECK(data.handle_radius_m == Approx(0.58));
  CHECK(data.sample_rate_hz == 1000.0);
  CHECK(contains(data.angle_source, "inclinometer_angle_rad"));
  CHECK(has_note(data, "anchored to inclinometer_angle_rad at 4 still periods"));
  CHECK(data.excluded.empty());
  REQUIRE(data.strokes.size() == 6);
  for (std::size_t k = 0; k < 6; ++k) {
    const Stroke& stroke = data.strokes[k];
    CHECK(stroke.id == static_cast<int>(k + 1));
    CHECK(stroke.direction == (k % 2 == 0 ? StrokeDirection::kOpening : StrokeDirection::kClosing));
    // The stroke column's samples, ids kept.
    CHECK(stroke.time_s.front() == Approx(s.starts[k].time_s).margin(1e-9));
    CHECK(stroke.size() == stroke.force_N.size());
    CHECK(stroke.size() == stroke.theta_rad.size());
    CHECK(stroke.size() == stroke.omega_rad_s.size());
  }
  // The door goes to 80°; over whole strokes the fused angle is within a few hundredths
  // of a degree of the truth (measured: 0.035° RMS, 0.081° at most), the rate within the
  // gyroscope's 0.05 °/s noise. The worst is the first cycle: the hand holds the door at 80°
  // (not a still period: it pushes), so the gyroscope's bias wanders for 5 s between two
  // anchors at the closed door, and only its mean change is removed.
  const Errors e = errors_against_truth(s, data.strokes);
  INFO("fused theta: RMS " << e.theta_rms / kRadPerDeg << " deg, max " << e.theta_max / kRadPerDeg
                           << " deg; omega RMS " << e.omega_rms / kRadPerDeg << " deg/s over "
                           << e.n << " samples");
  CHECK(e.n > 13000);
  CHECK(e.theta_rms < 0.05 * kRadPerDeg);
  CHECK(e.theta_max < 0.12 * kRadPerDeg);
  CHECK(e.omega_rms < 0.06 * kRadPerDeg);

  // The bias removed is the gyroscope's 0.2 °/s as it wandered during this session: the
  // mean of (rate − true rate).
  double bias_truth = 0;
  for (std::size_t i = 0; i < s.recording.size(); ++i) {
    bias_truth += (*s.recording.rate_rad_s)[i] - s.truth_omega[i];
  }
  bias_truth /= static_cast<double>(s.recording.size());
  INFO("bias: estimated " << data.gyro_bias_rad_s / kRadPerDeg << " deg/s, truth "
                          << bias_truth / kRadPerDeg);
  CHECK(std::abs(data.gyro_bias_rad_s / kRadPerDeg - 0.2) < 0.03);
  CHECK(std::abs(data.gyro_bias_rad_s - bias_truth) < 0.003 * kRadPerDeg);

  // Noise levels from the still periods: the inclinometer's 0.01° and the gyroscope's
  // 0.05 °/s (measured: 0.0098°, 0.0500 °/s).
  CHECK(data.angle_noise_rad / kRadPerDeg == Approx(0.01).epsilon(0.15));
  CHECK(data.rate_noise_rad_s / kRadPerDeg == Approx(0.05).epsilon(0.1));

  // prepare_session reads the same session to the same result.
  const PreparedData from_file = prepare_session(s.path);
  REQUIRE(from_file.strokes.size() == data.strokes.size());
  CHECK(from_file.strokes[3].theta_rad == data.strokes[3].theta_rad);
  CHECK(from_file.gyro_bias_rad_s == data.gyro_bias_rad_s);
}

TEST_CASE("Preprocessing: strokes found without the stroke column", "[preprocessing]") {
  const BenchSession& s = bench_session();
  Recording recording = s.recording;
  recording.stroke.reset();
  const PreparedData data = prepare(recording);
  REQUIRE(s.starts.size() == 6);
  REQUIRE(s.ends_s.size() == 6);
  REQUIRE(data.strokes.size() == 6);
  for (std::size_t k = 0; k < 6; ++k) {
    const Stroke& stroke = data.strokes[k];
    CHECK(stroke.id == static_cast<int>(k + 1));
    const bool opening = s.starts[k].detail == "opening";
    CHECK(stroke.direction == (opening ? StrokeDirection::kOpening : StrokeDirection::kClosing));
    // Starts within 50 ms of the hand's stroke event (measured: 3 to 25 ms before it).
    INFO("stroke " << k + 1 << " starts " << stroke.time_s.front() - s.starts[k].time_s
                   << " s after its event");
    CHECK(std::abs(stroke.time_s.front() - s.starts[k].time_s) < 0.05);
    // ... and holds all of the stroke's motion (the truth's |ω| > 1 °/s).
    for (std::size_t i = truth_index(s, s.starts[k].time_s); i < truth_index(s, s.ends_s[k]); ++i) {
      if (std::abs(s.truth_omega[i]) > 1.0 * kRadPerDeg) {
        CHECK(stroke.time_s.front() <= s.truth_time[i]);
        CHECK(stroke.time_s.back() >= s.truth_time[i]);
      }
    }
    // It starts at rest: its first sample is its initial state.
    CHECK(std::abs(stroke.omega_rad_s.front()) < 0.3 * kRadPerDeg);
  }
  // The door springs back by 0.3° when the hand lets go after each closing: listed, too
  // short for a stroke (measured: about 0.3 s, with the margins).
  REQUIRE(data.excluded.size() == 3);
  for (const ExcludedSegment& segment : data.excluded) {
    CHECK(contains(segment.reason, "too short"));
    CHECK(segment.end_s - segment.start_s < 0.4);
  }
  CHECK(errors_against_truth(s, data.strokes).theta_rms < 0.05 * kRadPerDeg);
}

TEST_CASE("Preprocessing: saturated and faulty segments are excluded and listed",
          "[preprocessing]") {
  const BenchSession& s = bench_session();
  Recording recording = s.recording;

  SECTION("a saturated gyroscope in a stroke") {
    // 40 ms in the middle of the second opening (stroke 3) at the gyroscope's +100 °/s,
    // where the door really turns at about 60 °/s.
    const std::size_t first = index_at(recording, 7.8);
    for (std::size_t i = first; i < first + 40; ++i)
      (*recording.rate_rad_s)[i] = 100.0 * kRadPerDeg;
    const PreparedData data = prepare(recording);
    // The part before the saturation is kept (its angle is known from the anchor before
    // it); the rest is listed.
    REQUIRE(data.excluded.size() == 1);
    const ExcludedSegment& segment = data.excluded.front();
    INFO(segment.reason);
    CHECK(contains(segment.reason, "stroke 3 (opening), after the part kept"));
    CHECK(contains(segment.reason, "gyroscope saturated"));
    CHECK(contains(segment.reason, "40 samples from 7.800 s"));
    CHECK(segment.start_s == Approx(7.800).margin(0.001));
    CHECK(segment.end_s == Approx(8.700).margin(0.001));
    REQUIRE(data.strokes.size() == 6);
    const Stroke& third = data.strokes[2];
    CHECK(third.id == 3);
    CHECK(third.time_s.front() == Approx(6.601).margin(0.001));
    CHECK(third.time_s.back() == Approx(7.799).margin(0.001));
    // The angle the bad samples added stays with them, but between the two anchors around
    // them the gyroscope's drift is no longer removed (the anchors' difference is put on the
    // lost samples): measured 0.11° RMS, 0.34° at most, on stroke 4.
    const Errors e = errors_against_truth(s, data.strokes);
    INFO("theta RMS " << e.theta_rms / kRadPerDeg << " deg, max " << e.theta_max / kRadPerDeg);
    CHECK(e.theta_rms < 0.2 * kRadPerDeg);
    CHECK(e.theta_max < 0.5 * kRadPerDeg);
  }
  SECTION("a negative saturation between strokes") {
    const std::size_t at = index_at(recording, 6.2);
    for (std::size_t i = at; i < at + 5; ++i) (*recording.rate_rad_s)[i] = -100.0 * kRadPerDeg;
    const PreparedData data = prepare(recording);
    REQUIRE(data.excluded.size() == 1);
    CHECK(contains(data.excluded.front().reason, "outside the strokes: gyroscope saturated"));
    CHECK(data.excluded.front().start_s == Approx(6.2).margin(1e-9));
    CHECK(data.excluded.front().end_s == Approx(6.204).margin(1e-9));
    REQUIRE(data.strokes.size() == 6);
    // As above: no drift removed between the anchors around the lost samples (measured
    // 0.49° at most).
    CHECK(errors_against_truth(s, data.strokes).theta_max < 0.7 * kRadPerDeg);
  }
  SECTION("a non-finite force") {
    (*recording.rate_rad_s).at(index_at(recording, 13.0)) = 0.0;  // a plain value
    recording.force_N.at(index_at(recording, 16.0)) = std::nan("");
    const PreparedData data = prepare(recording);
    // The longer part, after the bad sample, is kept.
    REQUIRE(data.excluded.size() == 1);
    INFO(data.excluded.front().reason);
    CHECK(contains(data.excluded.front().reason,
                   "stroke 6 (closing), before the part kept: non-finite force_N"));
    REQUIRE(data.strokes.size() == 6);
    CHECK(data.strokes[5].time_s.front() == Approx(16.001).margin(1e-6));
  }
  SECTION("a gap in the samples") {
    erase_rows(recording, index_at(recording, 4.0), 100);  // 0.1 s missing in stroke 2
    const PreparedData data = prepare(recording);
    // Longer than a bridged loss (0.05 s), but each side of it is anchored (the still
    // periods before and after the stroke): the stroke keeps both, the gap marked.
    REQUIRE(data.excluded.size() == 1);
    CHECK(data.excluded.front().reason ==
          "stroke 2 (closing): gap in time_s: no sample from 3.999 s to 4.100 s; the fit leaves "
          "out the windows that span it and fits the rest of the stroke");
    REQUIRE(data.strokes.size() == 6);
    CHECK(data.strokes[1].time_s.front() < 4.0);
    CHECK(data.strokes[1].time_s.back() > 4.1);
    REQUIRE(data.strokes[1].gap_before.size() == 1);
    CHECK(data.strokes[1].time_s[data.strokes[1].gap_before[0]] == Approx(4.1).margin(1e-9));
    const Errors e = errors_against_truth(s, data.strokes);
    INFO("theta RMS " << e.theta_rms / kRadPerDeg << " deg, max " << e.theta_max / kRadPerDeg);
    CHECK(e.theta_max < 0.7 * kRadPerDeg);
  }
}

TEST_CASE("Preprocessing: rate only integrates from theta = 0 at the first still period",
          "[preprocessing]") {
  const BenchSession& s = bench_session();
  const PreparedData data = prepare(without_inclinometer(s.recording));
  REQUIRE(data.strokes.size() == 6);
  CHECK(has_note(data, "theta = 0 at the still period from 0.100 s"));
  CHECK(has_note(data, "angle noise: the fallback figure"));
  CHECK(data.angle_noise_rad == Approx(0.01 * kRadPerDeg));
  // Without an absolute angle the bias's wandering between still periods adds up: measured
  // 0.14° RMS, 0.28° at most over 18 s (the hand holds the door open between strokes).
  const Errors e = errors_against_truth(s, data.strokes);
  INFO("rate only: theta RMS " << e.theta_rms / kRadPerDeg << " deg, max "
                               << e.theta_max / kRadPerDeg);
  CHECK(e.theta_rms < 0.2 * kRadPerDeg);
  CHECK(e.omega_rms < 0.08 * kRadPerDeg);
}

TEST_CASE("Preprocessing: a CSV of an exact simulator run (full-range angle_rad)",
          "[preprocessing]") {
  const Trajectory run = exact_run();
  const auto path = fresh_path("exact-run.csv");
  write_recording_csv_file(path, to_recording(run, "test_preprocessing exact run"));
  const Recording recording = read_recording_csv(path);
  REQUIRE(recording.angle_rad.has_value());
  REQUIRE(recording.rate_rad_s.has_value());

  auto check_strokes = [&](const PreparedData& data, double omega_tolerance_rad_s) {
    REQUIRE(data.strokes.size() == 2);
    CHECK(data.strokes[0].direction == StrokeDirection::kOpening);
    CHECK(data.strokes[1].direction == StrokeDirection::kClosing);
    double sq = 0, count = 0;
    for (const Stroke& stroke : data.strokes) {
      for (std::size_t k = 0; k < stroke.size(); ++k) {
        const auto i = static_cast<std::size_t>(std::llround(stroke.time_s[k] * 1000.0));
        REQUIRE(run.time_s[i] == stroke.time_s[k]);
        CHECK(stroke.theta_rad[k] == run.theta_rad[i]);  // angle_rad is used as it is
        CHECK(stroke.force_N[k] == run.force_N[i]);
        sq += std::pow(stroke.omega_rad_s[k] - run.omega_rad_s[i], 2);
        count += 1;
      }
    }
    const double omega_rms = std::sqrt(sq / count);
    INFO("omega RMS " << omega_rms / kRadPerDeg << " deg/s");
    CHECK(omega_rms < omega_tolerance_rad_s);
  };

  SECTION("angle and rate: the rate needs no correction") {
    const PreparedData data = prepare(recording);
    CHECK(data.handle_radius_m == run.handle_radius_m);
    CHECK(std::abs(data.gyro_bias_rad_s) < 0.001 * kRadPerDeg);
    CHECK(data.strokes[0].id == 1);
    CHECK(data.strokes[1].id == 2);
    check_strokes(data, 0.001 * kRadPerDeg);
    // Noise-free: the estimates sit at their floors, 1% of the bench's figures.
    CHECK(data.angle_noise_rad == Approx(1e-4 * kRadPerDeg));
    CHECK(data.rate_noise_rad_s == Approx(5e-4 * kRadPerDeg));
  }
  SECTION("angle only: the rate is the zero-phase derivative") {
    Recording angle_only = recording;
    angle_only.rate_rad_s.reset();
    const PreparedData data = prepare(angle_only);
    CHECK(has_note(data, "zero-phase low-pass at 30 Hz"));
    CHECK(data.gyro_bias_rad_s == 0.0);
    // Measured: 0.10 °/s RMS, from the latch's and the stops' sharp turns.
    check_strokes(data, 0.15 * kRadPerDeg);
    SECTION("and without the stroke column") {
      angle_only.stroke.reset();
      check_strokes(prepare(angle_only), 0.15 * kRadPerDeg);
    }
  }
}

TEST_CASE("Preprocessing: motion segments merge across short pauses", "[preprocessing]") {
  // An exact angle: rest, 0 → 20° in 1 s, a pause, 20 → 40° in 1 s, rest, 40 → 0 in 1.5 s,
  // rest (minimum-jerk moves).
  auto recording_with_pause = [](double pause_s) {
    struct Move {
      double start_s, duration_s, from_deg, to_deg;
    };
    const std::vector<Move> moves = {
        {1.0, 1.0, 0, 20}, {2.0 + pause_s, 1.0, 20, 40}, {4.0 + pause_s, 1.5, 40, 0}};
    Recording recording;
    recording.source = "mem";
    recording.angle_rad.emplace();
    for (std::size_t i = 0; static_cast<double>(i) <= (6.5 + pause_s) * 1000.0; ++i) {
      const double t = static_cast<double>(i) / 1000.0;
      double angle_deg = 0;
      for (const Move& move : moves) {
        if (t < move.start_s) break;
        const double s = std::min((t - move.start_s) / move.duration_s, 1.0);
        angle_deg =
            move.from_deg + (move.to_deg - move.from_deg) * s * s * s * (10 - 15 * s + 6 * s * s);
      }
      recording.time_s.push_back(t);
      recording.force_N.push_back(0.0);
      recording.angle_rad->push_back(angle_deg * kRadPerDeg);
    }
    return recording;
  };
  // A pause of 0.2 s (below merge_gap_s = 0.3 s): one opening of 40°, then the closing.
  const PreparedData merged = prepare(recording_with_pause(0.2));
  REQUIRE(merged.strokes.size() == 2);
  CHECK(merged.strokes[0].direction == StrokeDirection::kOpening);
  CHECK(merged.strokes[0].time_s.front() == Approx(0.9).margin(0.05));
  CHECK(merged.strokes[0].time_s.back() == Approx(3.3).margin(0.05));
  CHECK(merged.strokes[1].direction == StrokeDirection::kClosing);
  CHECK(merged.strokes[1].time_s.front() == Approx(4.1).margin(0.05));
  // A pause of 0.6 s: two openings of 20°.
  const PreparedData apart = prepare(recording_with_pause(0.6));
  REQUIRE(apart.strokes.size() == 3);
  CHECK(apart.strokes[0].direction == StrokeDirection::kOpening);
  CHECK(apart.strokes[1].direction == StrokeDirection::kOpening);
  CHECK(apart.strokes[2].direction == StrokeDirection::kClosing);
  CHECK(apart.strokes[1].theta_rad.back() - apart.strokes[1].theta_rad.front() ==
        Approx(20 * kRadPerDeg).margin(0.01 * kRadPerDeg));
  CHECK(apart.excluded.empty());
}

TEST_CASE("Preprocessing: the zero-phase low-pass and derivative", "[preprocessing]") {
  const double rate_hz = 1000.0;
  std::vector<double> time(4000), slow(4000), at_cutoff(4000), line(4000);
  for (std::size_t i = 0; i < time.size(); ++i) {
    time[i] = static_cast<double>(i) / rate_hz;
    slow[i] = std::sin(2 * std::numbers::pi * 2.0 * time[i]);
    at_cutoff[i] = std::sin(2 * std::numbers::pi * 30.0 * time[i]);
    line[i] = 0.3 + 1.7 * time[i];
  }
  const std::vector<double> a = zero_phase_lowpass(slow, 30.0, rate_hz);
  const std::vector<double> b = zero_phase_lowpass(at_cutoff, 30.0, rate_hz);
  const std::vector<double> c = zero_phase_lowpass(line, 30.0, rate_hz);
  const std::vector<double> d = smoothing_derivative(time, line, 30.0, rate_hz);
  // Away from the ends: no delay, gain 1 well below the cut-off and 1/2 at it.
  for (std::size_t i = 500; i < 3500; ++i) {
    CHECK(a[i] == Approx(slow[i]).margin(1e-3));
    CHECK(b[i] == Approx(0.5 * at_cutoff[i]).margin(2e-3));
  }
  for (std::size_t i = 0; i < time.size(); ++i) {
    CHECK(c[i] == Approx(line[i]).margin(1e-9));
    CHECK(d[i] == Approx(1.7).margin(1e-6));
  }
  CHECK_THROWS_AS(zero_phase_lowpass(slow, 500.0, rate_hz), std::invalid_argument);
}

TEST_CASE("Preprocessing: options and error messages", "[preprocessing]") {
  PreprocessingOptions options;
  CHECK(options.validate().empty());
  options.still_window_s = -1;
  CHECK(options.validate() == "preprocessing still_window_s = -1 must be > 0");
  CHECK_THROWS_WITH(prepare(synthetic(100), options),
                    "preprocessing still_window_s = -1 must be > 0");
  options = {};
  options.inclinometer_margin_rad = options.inclinometer_range_rad;
  CHECK(contains(options.validate(), "inclinometer_margin_rad"));
  options = {};
  options.force_cutoff_hz = std::nan("");
  CHECK(options.validate() == "preprocessing force_cutoff_hz = nan must be finite");

  Recording recording = synthetic(2000);
  CHECK(error_of(recording) == "mem: neither rate_rad_s nor angle_rad (at least one is needed)");
  CHECK(error_of(synthetic(5)) == "mem: too few samples to prepare (5; at least 10 needed)");

  // Rate only, always moving at 10 °/s: nothing to take the bias or theta = 0 from.
  recording.rate_rad_s = std::vector<double>(2000, 10.0 * kRadPerDeg);
  CHECK(contains(error_of(recording),
                 "mem: rate_rad_s only, and no still period to estimate the gyroscope bias"));
  // Still, but the inclinometer beyond its range: nothing to anchor to.
  recording.rate_rad_s = std::vector<double>(2000, 0.2 * kRadPerDeg);
  recording.extra_names = {"inclinometer_angle_rad"};
  recording.extra_columns = {std::vector<double>(2000, 10.0 * kRadPerDeg)};
  CHECK(contains(error_of(recording),
                 "mem: no still period with the inclinometer (inclinometer_angle_rad) inside "
                 "+-9.5 deg to anchor the integrated gyroscope to (1 still periods found;"));
  // In range, it works (and the door stays where the inclinometer says).
  recording.extra_columns = {std::vector<double>(2000, 5.0 * kRadPerDeg)};
  const PreparedData data = prepare(recording);
  CHECK(data.strokes.empty());
  CHECK(data.gyro_bias_rad_s == Approx(0.2 * kRadPerDeg));

  PreprocessingOptions named;
  named.inclinometer_column = "incl_deg";
  CHECK(error_of(recording, named) == "mem: no column incl_deg (the inclinometer_column option)");
  recording.extra_columns[0].pop_back();
  CHECK(error_of(recording) ==
        "mem: column inclinometer_angle_rad has 1999 values, time_s has 2000");
  recording.extra_columns[0].push_back(0.0);
  recording.time_s[7] = recording.time_s[6];
  CHECK(error_of(recording) ==
        "mem: time_s must be finite and strictly increasing (row 8 of the data)");
}
