#pragma once
// A family of recording conditions for the residual loop's tests and benchmarks
// (docs/residual-loop.md, "The recording family"): not one generator but conditions drawn per
// recording, so that no test tunes to one recording.
//
//   RecordingConditions c = draw_conditions(seed);          // or draw_conditions(seed, options)
//   PreparedData data = family_recording(truth, c, seed);   // c.describe() for messages
//
// What varies (FamilyOptions holds the ranges; the defaults are the whole family):
//   hand     "pd": an impedance (PD) grip of 300–3000 N/m tracking minimum-jerk moves;
//            "minimum-jerk": a stiff grip (4000–10000 N/m), the door follows the moves;
//            "robot": a stiff grip moving at a constant speed (0.15–0.8 rad/s, 0.1 s ramps);
//            "impulse": the hand sets the door at a start angle (0.1–1.2 rad), lets go, and
//            gives it a short push (half-sine, 60–150 ms) open, then one closed from where it
//            stopped; only the pushes and the coasting are strokes (the study's way to see
//            friction at every angle).
//   tremor   none, or three sinusoids in a band (1–8 Hz or 8–12 Hz) of 0.05–0.5 N together,
//            scaled by the grip (the pushes of the impulse hand are free of it);
//   pauses   a pause of 0.3–1 s halfway through each opening (a stop within the stroke);
//   latch    closings pushed through the latch (aiming 0.03–0.08 rad past closed) or stopped
//            at 0.1–0.25 rad and let go there (the door is closed afterwards, outside strokes);
//   rate     50, 100, 200, 500 or 1000 Hz, the intervals jittered by up to ±10 % (uniform);
//   sensors  "inclinometer+gyro": the bench's gyroscope (±100 °/s, saturating; 0.05 °/s noise;
//            a bias of up to ±0.5 °/s) and inclinometer (±10 °, saturating; 10 Hz first-order
//            lag; 0.01 ° noise), prepared by `prepare` as a session is (rate with the bias
//            removed, the integrated angle anchored to the inclinometer at rest);
//            "encoder": an angle quantised to 2π / counts (4096–65536 counts per turn), no rate;
//            "angle": an angle with 0.01 ° noise, no rate. Both are prepared by `prepare`, which
//            derives the rate as it does for a user's angle-only CSV (zero-phase low-pass,
//            derivative; docs/preprocessing.md);
//            "state": the simulated angle and rate with the bench's noise, not prepared (as the
//            tremor-hand and virtual-hand generators make them);
//   noise    the bench's force, angle and rate noise times 0.5–2.
// Every drawn recording is `strokes` strokes (opening, closing, alternating; ids 1, 2, ...)
// in runs of two that start and end with the door at rest at closed (0.6 s of rest
// between runs, so that `prepare` finds still periods), 0.25 s of rest kept before each
// stroke. The door is simulated under the hand and sampled at the (jittered) sample times,
// the hand's force with it: the fit's linear interpolation of the force between samples is
// then an approximation, as on a real bench (RecordingConditions::replay_sampled_force for
// the other generators' way).
// `prepare` may leave strokes out (a saturated gyroscope, too short): PreparedData::excluded.
//
// Contract: deterministic for (conditions, seed); draw_conditions deterministic for
// (seed, options). Throws std::invalid_argument for conditions it cannot make (unknown
// hand or sensors, strokes < 2, a rate below 20 Hz). Header-only, test and benchmark code.
// Thread safety: free functions without shared state.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "acquisition/session/recording_csv.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/preprocessing/strokes.h"
#include "analysis/simulation/simulator.h"
#include "core/number_format.h"
#include "core/units.h"

namespace doorbench::testing {

// One drawn set of conditions (see the header comment for each field's meaning).
struct RecordingConditions {
  std::string hand = "pd";  // "pd", "minimum-jerk", "robot", "impulse"
  int strokes = 12;
  double sample_rate_hz = 1000.0;
  double jitter_fraction = 0.0;  // each interval ± up to this share of 1 / rate (uniform)
  std::string sensors = "inclinometer+gyro";  // "encoder", "angle", "state"
  // The grip's impedance along the handle's arc.
  double grip_stiffness_N_per_m = 2000.0;
  double grip_damping_N_s_per_m = 60.0;
  // Moves: the openings' target angles (drawn per run in this range), the peak speed of the
  // minimum-jerk moves, the robot's constant speed, the impulse hand's start angles and
  // coasting speeds (the speed each push aims to give).
  double open_min_rad = 0.35, open_max_rad = 1.4;
  double peak_speed_rad_s = 0.9;
  double robot_speed_rad_s = 0.4;
  double impulse_start_min_rad = 0.1, impulse_start_max_rad = 1.2;
  double impulse_speed_min_rad_s = 0.5, impulse_speed_max_rad_s = 1.3;
  // Tremor: three sinusoids in [low, high] Hz of tremor_force_N together (0: none).
  double tremor_low_hz = 8.0, tremor_high_hz = 12.0;
  double tremor_force_N = 0.0;
  double pause_s = 0.0;               // a pause halfway through each opening (0: none)
  bool latch = true;                  // closings pushed through the latch
  double latch_overshoot_rad = 0.05;  // how far past closed the closing aims (latch)
  double stop_short_rad = 0.15;       // where the closing stops (no latch)
  // Sensors and noise (standard deviations per sample).
  double force_noise_N = 0.2;
  double angle_noise_rad = 0.01 * kRadPerDeg;   // inclinometer, angle
  double rate_noise_rad_s = 0.05 * kRadPerDeg;  // gyroscope, state
  double gyro_bias_rad_s = 0.0;
  double gyro_range_rad_s = 100.0 * kRadPerDeg;
  double inclinometer_range_rad = 10.0 * kRadPerDeg;
  double inclinometer_bandwidth_hz = 10.0;
  int encoder_counts = 16384;  // per turn
  // The data are the door as the hand moved it, sampled (a continuous force, as a real
  // bench samples it); true: the door simulated again under the sampled force, linearly
  // interpolated (as fit_synthetic's and the tremor hand's generators do), so that the data
  // are exactly what a model driven by the recorded force does. At low rates that replay is
  // another door: a stiff grip's force, sampled at 50 Hz, left the door standing.
  bool replay_sampled_force = false;

  // One line for tables and failure messages, e.g. "pd 1200 N/m, 1000 Hz ±5 %,
  // inclinometer+gyro, tremor 0.3 N 1-8 Hz, latch, openings 1.05-1.34 rad, ...".
  std::string describe() const {
    std::string text = hand;
    if (hand != "impulse") {
      text.append(
          printf_text(" %.0f N/m %.0f N s/m", grip_stiffness_N_per_m, grip_damping_N_s_per_m));
    }
    text.append(printf_text(", %d strokes, %g Hz", strokes, sample_rate_hz));
    if (jitter_fraction > 0) text.append(printf_text(" jitter ±%.0f %%", 100.0 * jitter_fraction));
    text.append(", ").append(sensors);
    if (sensors == "encoder") text.append(printf_text(" %d counts", encoder_counts));
    if (sensors == "inclinometer+gyro") {
      text.append(printf_text(" (bias %.2f deg/s)", gyro_bias_rad_s * kDegPerRad));
    }
    if (tremor_force_N > 0) {
      text.append(
          printf_text(", tremor %.2f N %g-%g Hz", tremor_force_N, tremor_low_hz, tremor_high_hz));
    } else {
      text.append(", no tremor");
    }
    if (hand == "impulse") {
      text.append(printf_text(", starts %.2f-%.2f rad, coasting %.2f-%.2f rad/s",
                              impulse_start_min_rad, impulse_start_max_rad, impulse_speed_min_rad_s,
                              impulse_speed_max_rad_s));
    } else {
      text.append(printf_text(", openings %.2f-%.2f rad", open_min_rad, open_max_rad));
      text.append(hand == "robot" ? printf_text(" at %.2f rad/s", robot_speed_rad_s)
                                  : printf_text(" peak %.2f rad/s", peak_speed_rad_s));
      if (pause_s > 0) text.append(printf_text(", pause %.2f s", pause_s));
      text.append(latch ? printf_text(", latch (aim %.3f rad past closed)", latch_overshoot_rad)
                        : printf_text(", no latch (stop at %.3f rad)", stop_short_rad));
    }
    if (replay_sampled_force) text.append(", replayed under the sampled force");
    text.append(printf_text(", noise %.2f N %.4f deg %.3f deg/s", force_noise_N,
                            angle_noise_rad * kDegPerRad, rate_noise_rad_s * kDegPerRad));
    return text;
  }
};

// The ranges to draw from; the defaults are the whole family. A list is drawn from
// uniformly, a [min, max] pair uniformly in between.
struct FamilyOptions {
  int strokes = 12;
  std::vector<std::string> hands = {"pd", "minimum-jerk", "robot", "impulse"};
  std::vector<double> sample_rates_hz = {50.0, 100.0, 200.0, 500.0, 1000.0};
  double max_jitter_fraction = 0.1;
  std::vector<std::string> sensors = {"inclinometer+gyro", "encoder", "angle"};
  // Tremor: none with this probability, else a band from the list and a size in range.
  double no_tremor_probability = 0.3;
  std::vector<std::pair<double, double>> tremor_bands_hz = {{1.0, 8.0}, {8.0, 12.0}};
  double tremor_min_N = 0.05, tremor_max_N = 0.5;
  double pause_probability = 0.3;
  double latch_probability = 0.7;
  double open_min_rad = 0.35, open_max_rad = 1.4;  // the openings' targets
  double noise_min_factor = 0.5, noise_max_factor = 2.0;
};

namespace family_detail {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRest_s = 0.6;     // at closed, between runs
constexpr double kLead_s = 0.25;    // rest kept in a stroke before it moves
constexpr double kHold_s = 0.3;     // the hand holds after a closing
constexpr double kRelease_s = 0.2;  // and lets go over this
constexpr double kMaxHandForce_N = 250.0;

// A reference move from `from` to `to` starting at `start` lasting `duration`: minimum-jerk,
// or (constant_speed) a constant speed with 0.1 s smooth ramps.
struct Move {
  double start = 0.0, duration = 1.0, from = 0.0, to = 0.0;
  bool constant_speed = false;
  void at(double t, double& theta, double& omega) const {
    const double s = std::clamp((t - start) / duration, 0.0, 1.0);
    const double span = to - from;
    if (!constant_speed) {
      theta = from + span * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
      omega = span / duration * 30.0 * s * s * (1.0 - s) * (1.0 - s);
      return;
    }
    // Trapezoid in speed: ramps of r (a share of the move) at both ends.
    const double r = std::min(0.45, 0.1 / duration);
    const double v = 1.0 / (1.0 - r);  // peak of ds/dτ for a unit move
    double p = 0.0, dp = 0.0;
    if (s < r) {
      p = 0.5 * v * s * s / r;
      dp = v * s / r;
    } else if (s > 1.0 - r) {
      const double q = 1.0 - s;
      p = 1.0 - 0.5 * v * q * q / r;
      dp = v * q / r;
    } else {
      p = 0.5 * v * r + v * (s - r);
      dp = v;
    }
    theta = from + span * p;
    omega = span / duration * dp;
  }
  double end() const { return start + duration; }
};

// Three sinusoids in a band, their amplitudes summing to `force_N`.
struct Tremor {
  double frequency_hz[3] = {0, 0, 0}, phase_rad[3] = {0, 0, 0}, amplitude_N[3] = {0, 0, 0};
  Tremor() = default;
  Tremor(double low_hz, double high_hz, double force_N, std::mt19937& random) {
    std::uniform_real_distribution<double> f(low_hz, high_hz), phase(0.0, 2.0 * kPi),
        weight(0.5, 1.0);
    double total = 0.0;
    for (int k = 0; k < 3; ++k) {
      frequency_hz[k] = f(random);
      phase_rad[k] = phase(random);
      amplitude_N[k] = weight(random);
      total += amplitude_N[k];
    }
    for (double& a : amplitude_N) a *= force_N / total;
  }
  double at(double t) const {
    double value = 0.0;
    for (int k = 0; k < 3; ++k) {
      value += amplitude_N[k] * std::sin(2.0 * kPi * frequency_hz[k] * t + phase_rad[k]);
    }
    return value;
  }
};

// The hand over one segment of a recording: a grip (impedance along the arc) tracking a
// sequence of moves (holding between them), its grip falling smoothly to 0 over
// [release_start, release_start + kRelease_s] (never, when release_start is infinite),
// plus tremor scaled by the grip; or, with a push, a half-sine force and no grip.
class SegmentHand final : public UserForce {
 public:
  double handle_radius_m = 0.58, stiffness_N_per_m = 2000.0, damping_N_s_per_m = 60.0;
  double hold_rad = 0.0;  // the reference before the first move
  std::vector<Move> moves;
  double release_start = INFINITY;
  Tremor tremor;
  double push_start = 0.0, push_duration = 0.0, push_N = 0.0;  // push_duration 0: no push

  double force_N(double t, double theta, double omega) const override {
    if (push_duration > 0) {
      if (t < push_start || t > push_start + push_duration) return 0.0;
      return push_N * std::sin(kPi * (t - push_start) / push_duration);
    }
    double grip = 1.0;
    if (t > release_start) {
      const double s = std::clamp((t - release_start) / kRelease_s, 0.0, 1.0);
      grip = 1.0 - s * s * (3.0 - 2.0 * s);
    }
    if (grip <= 0.0) return 0.0;
    double reference = hold_rad, reference_rate = 0.0;
    for (const Move& move : moves) {
      if (t >= move.start) move.at(t, reference, reference_rate);
    }
    const double force = stiffness_N_per_m * handle_radius_m * (reference - theta) +
                         damping_N_s_per_m * handle_radius_m * (reference_rate - omega);
    return grip * (std::clamp(force, -kMaxHandForce_N, kMaxHandForce_N) + tremor.at(t));
  }
};

// The recording being built: the sample times, and the door simulated segment by segment
// under the hand (the force it applied sampled at those times), with each sample's stroke id.
struct Builder {
  const DoorModel& truth;
  const RecordingConditions& conditions;
  std::mt19937& random;
  std::vector<double> times, force, theta, omega;
  std::vector<int> stroke;
  DoorState state;
  double interval_s;

  Builder(const DoorModel& model, const RecordingConditions& c, std::mt19937& r)
      : truth(model), conditions(c), random(r), interval_s(1.0 / c.sample_rate_hz) {
    times.push_back(0.0);
    force.push_back(0.0);
    theta.push_back(0.0);
    omega.push_back(0.0);
    stroke.push_back(0);
  }
  double now() const { return times.back(); }
  double next_time() {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double nominal = (std::round(now() / interval_s) + 1.0) * interval_s;
    return std::max(now() + 0.05 * interval_s,
                    nominal + conditions.jitter_fraction * interval_s * u(random));
  }
  // Simulates the door under `hand` up to `end_s`, marking the samples with `id`.
  void run(const UserForce& hand, double end_s, int id) {
    std::vector<double> out{now()};
    while (true) {
      const double t = next_time();
      if (t > end_s) break;
      out.push_back(t);
      times.push_back(t);  // reserve the order; values filled below
      stroke.push_back(id);
    }
    times.resize(times.size() - (out.size() - 1));
    stroke.resize(stroke.size() - (out.size() - 1));
    if (out.size() < 2) return;
    DoorState start = state;
    start.time_s = out.front();
    const Trajectory part = simulate(truth, hand, start, out);
    for (std::size_t i = 1; i < part.size(); ++i) {
      times.push_back(part.time_s[i]);
      force.push_back(part.force_N[i]);
      theta.push_back(part.theta_rad[i]);
      omega.push_back(part.omega_rad_s[i]);
      stroke.push_back(id);
    }
    state = {part.time_s.back(), part.theta_rad.back(), part.omega_rad_s.back(), 0.0};
  }
  SegmentHand grip_hand() const {
    SegmentHand hand;
    hand.handle_radius_m = truth.geometry().handle_radius_m;
    hand.stiffness_N_per_m = conditions.grip_stiffness_N_per_m;
    hand.damping_N_s_per_m = conditions.grip_damping_N_s_per_m;
    hand.hold_rad = state.theta_rad;
    return hand;
  }
  Move move_to(double start, double to) const {
    Move move{start, 1.0, state.theta_rad, to, conditions.hand == "robot"};
    const double distance = std::abs(to - state.theta_rad);
    move.duration = conditions.hand == "robot" ? distance / conditions.robot_speed_rad_s + 0.1
                                               : 1.875 * distance / conditions.peak_speed_rad_s;
    move.duration = std::max(move.duration, 0.3);
    return move;
  }
  // The hand closes the door from wherever it is into the latch and lets go; then rest.
  void return_to_closed(Tremor tremor) {
    SegmentHand hand = grip_hand();
    hand.tremor = tremor;
    hand.moves.push_back(move_to(now() + 0.2, -0.05));
    hand.release_start = hand.moves.back().end() + kHold_s;
    run(hand, hand.release_start + kRelease_s + kRest_s, 0);
  }
};

inline Tremor draw_tremor(const RecordingConditions& c, std::mt19937& random) {
  return c.tremor_force_N > 0 ? Tremor(c.tremor_low_hz, c.tremor_high_hz, c.tremor_force_N, random)
                              : Tremor();
}

// One run of a grip hand: an opening (stroke id), a pause, a closing (id + 1).
inline void grip_run(Builder& b, double target_rad, int id) {
  const RecordingConditions& c = b.conditions;
  SegmentHand opening = b.grip_hand();
  opening.tremor = draw_tremor(c, b.random);
  if (c.pause_s > 0) {
    const double middle = 0.5 * (b.state.theta_rad + target_rad);
    const Move first = b.move_to(b.now() + kLead_s, middle);
    opening.moves.push_back(first);
    Move second = first;
    second.start = first.end() + c.pause_s;
    second.from = middle;
    second.to = target_rad;
    opening.moves.push_back(second);
  } else {
    opening.moves.push_back(b.move_to(b.now() + kLead_s, target_rad));
  }
  b.run(opening, opening.moves.back().end(), id);
  std::uniform_real_distribution<double> pause(0.3, 0.8);
  SegmentHand held = b.grip_hand();
  held.hold_rad = target_rad;
  held.tremor = opening.tremor;
  b.run(held, b.now() + pause(b.random) - kLead_s, 0);
  SegmentHand closing = b.grip_hand();
  closing.tremor = opening.tremor;
  const double end_rad = c.latch ? -c.latch_overshoot_rad : c.stop_short_rad;
  closing.moves.push_back(b.move_to(b.now() + kLead_s, end_rad));
  closing.release_start = closing.moves.back().end() + kHold_s;
  b.run(closing, closing.release_start + kRelease_s, id + 1);
  if (c.latch) {
    b.run(SegmentHand{closing}, b.now() + kRest_s, 0);
  } else {
    b.run(closing, b.now() + 0.3, 0);
    b.return_to_closed(opening.tremor);
  }
}

// One run of the impulse hand: the hand sets the door at `start_rad` and lets go; a push
// opens it (stroke id), a push closes it from where it stopped (id + 1); the hand closes it.
inline void impulse_run(Builder& b, double start_rad, int id) {
  const RecordingConditions& c = b.conditions;
  const Tremor tremor = draw_tremor(c, b.random);
  SegmentHand setting = b.grip_hand();
  setting.tremor = tremor;
  setting.moves.push_back(b.move_to(b.now() + 0.2, start_rad));
  setting.release_start = setting.moves.back().end() + kHold_s;
  b.run(setting, setting.release_start + kRelease_s + 0.4 - kLead_s, 0);
  std::uniform_real_distribution<double> speed(c.impulse_speed_min_rad_s,
                                               c.impulse_speed_max_rad_s),
      duration(0.06, 0.15);
  const double r_h = b.truth.geometry().handle_radius_m;
  for (int direction : {1, -1}) {
    SegmentHand push;
    push.push_start = b.now() + kLead_s;
    push.push_duration = duration(b.random);
    // A half-sine of peak P gives r_h P T 2/π of angular impulse; add the friction to beat.
    const double friction_Nm = std::abs(b.truth.torque_Nm(b.state.theta_rad, 0.05 * direction));
    const double impulse_Nms = b.truth.inertia_kg_m2() * speed(b.random);
    push.push_N = direction * (impulse_Nms * kPi / (2.0 * push.push_duration) + friction_Nm) / r_h;
    b.run(push, push.push_start + push.push_duration + 1.6, id + (direction < 0 ? 1 : 0));
  }
  b.return_to_closed(tremor);
}

// Makes a RecordingConditions' sensors from the simulated door: the Recording a user's CSV
// or session would give (for `prepare`).
inline Recording sensor_recording(const Builder& b, const Trajectory& door, std::mt19937& random) {
  const RecordingConditions& c = b.conditions;
  std::normal_distribution<double> normal(0.0, 1.0);
  Recording recording;
  recording.source = "recording family";
  recording.handle_radius_m = b.truth.geometry().handle_radius_m;
  recording.sample_rate_hz = c.sample_rate_hz;
  recording.time_s = door.time_s;
  recording.stroke = b.stroke;
  const std::size_t n = door.size();
  recording.force_N.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    recording.force_N[i] = door.force_N[i] + c.force_noise_N * normal(random);
  }
  if (c.sensors == "inclinometer+gyro") {
    std::vector<double> rate(n), inclinometer(n);
    double lagged = door.theta_rad[0];
    for (std::size_t i = 0; i < n; ++i) {
      const double dt = i > 0 ? door.time_s[i] - door.time_s[i - 1] : 0.0;
      lagged += (1.0 - std::exp(-2.0 * kPi * c.inclinometer_bandwidth_hz * dt)) *
                (door.theta_rad[i] - lagged);
      rate[i] =
          std::clamp(door.omega_rad_s[i] + c.gyro_bias_rad_s + c.rate_noise_rad_s * normal(random),
                     -c.gyro_range_rad_s, c.gyro_range_rad_s);
      inclinometer[i] = std::clamp(lagged + c.angle_noise_rad * normal(random),
                                   -c.inclinometer_range_rad, c.inclinometer_range_rad);
    }
    recording.rate_rad_s = std::move(rate);
    recording.extra_names = {"inclinometer_angle_rad"};
    recording.extra_columns = {std::move(inclinometer)};
  } else {
    std::vector<double> angle(n);
    const double count_rad = 2.0 * kPi / c.encoder_counts;
    for (std::size_t i = 0; i < n; ++i) {
      angle[i] = c.sensors == "encoder" ? count_rad * std::round(door.theta_rad[i] / count_rad)
                                        : door.theta_rad[i] + c.angle_noise_rad * normal(random);
    }
    recording.angle_rad = std::move(angle);
  }
  return recording;
}

// The "state" sensors: the simulated angle and rate with noise, cut by the stroke ids.
inline PreparedData state_data(const Builder& b, const Trajectory& door, std::mt19937& random) {
  const RecordingConditions& c = b.conditions;
  std::normal_distribution<double> normal(0.0, 1.0);
  PreparedData data;
  data.source = "recording family";
  data.handle_radius_m = b.truth.geometry().handle_radius_m;
  data.sample_rate_hz = c.sample_rate_hz;
  data.rate_noise_rad_s = c.rate_noise_rad_s;
  data.angle_noise_rad = c.angle_noise_rad;
  data.angle_source = "the simulated angle with noise";
  for (std::size_t i = 0; i < door.size(); ++i) {
    const int id = b.stroke[i];
    if (id == 0) continue;
    if (data.strokes.empty() || data.strokes.back().id != id) {
      Stroke stroke;
      stroke.id = id;
      stroke.direction = id % 2 == 1 ? StrokeDirection::kOpening : StrokeDirection::kClosing;
      data.strokes.push_back(std::move(stroke));
    }
    Stroke& s = data.strokes.back();
    s.time_s.push_back(door.time_s[i]);
    s.force_N.push_back(door.force_N[i] + c.force_noise_N * normal(random));
    s.theta_rad.push_back(door.theta_rad[i] + c.angle_noise_rad * normal(random));
    s.omega_rad_s.push_back(door.omega_rad_s[i] + c.rate_noise_rad_s * normal(random));
  }
  return data;
}

template <typename T>
const T& pick(const std::vector<T>& values, std::mt19937& random) {
  if (values.empty()) throw std::invalid_argument("recording family: an empty list to draw from");
  std::uniform_int_distribution<std::size_t> index(0, values.size() - 1);
  return values[index(random)];
}

}  // namespace family_detail

// Draws one set of conditions from `options`' ranges (see the header comment).
inline RecordingConditions draw_conditions(std::uint32_t seed, const FamilyOptions& options = {}) {
  using family_detail::pick;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto between = [&](double low, double high) { return low + (high - low) * unit(random); };
  RecordingConditions c;
  c.strokes = options.strokes;
  c.hand = pick(options.hands, random);
  c.sample_rate_hz = pick(options.sample_rates_hz, random);
  c.jitter_fraction = between(0.0, options.max_jitter_fraction);
  c.sensors = pick(options.sensors, random);
  if (c.hand == "pd") {
    c.grip_stiffness_N_per_m = std::exp(between(std::log(300.0), std::log(3000.0)));
    c.grip_damping_N_s_per_m = between(20.0, 100.0);
  } else {
    c.grip_stiffness_N_per_m = between(4000.0, 10000.0);
    c.grip_damping_N_s_per_m = between(60.0, 150.0);
  }
  c.open_min_rad = options.open_min_rad;
  c.open_max_rad = options.open_max_rad;
  c.peak_speed_rad_s = between(0.5, 1.3);
  c.robot_speed_rad_s = between(0.15, 0.8);
  if (unit(random) >= options.no_tremor_probability) {
    const std::pair<double, double>& band = pick(options.tremor_bands_hz, random);
    c.tremor_low_hz = band.first;
    c.tremor_high_hz = band.second;
    c.tremor_force_N = between(options.tremor_min_N, options.tremor_max_N);
  }
  c.pause_s = unit(random) < options.pause_probability ? between(0.3, 1.0) : 0.0;
  c.latch = unit(random) < options.latch_probability;
  c.latch_overshoot_rad = between(0.03, 0.08);
  c.stop_short_rad = between(0.1, 0.25);
  const double noise = between(options.noise_min_factor, options.noise_max_factor);
  c.force_noise_N *= noise;
  c.angle_noise_rad *= noise;
  c.rate_noise_rad_s *= noise;
  c.gyro_bias_rad_s = between(-0.5, 0.5) * kRadPerDeg;
  const int counts[] = {4096, 16384, 65536};
  c.encoder_counts = counts[std::uniform_int_distribution<int>(0, 2)(random)];
  return c;
}

// The family of tests/analysis/test_residual_loop_family.cpp and studies/breakaway_oracle.cpp:
// the hands that take the door through low speeds (PD, minimum-jerk, impulses) at 100 Hz to
// 1 kHz, with the bench's inclinometer + gyroscope or an angle alone.
inline FamilyOptions breakaway_test_family() {
  FamilyOptions options;
  options.sensors = {"inclinometer+gyro", "angle"};
  options.hands = {"pd", "minimum-jerk", "impulse"};
  options.sample_rates_hz = {100.0, 200.0, 500.0, 1000.0};
  return options;
}

// The recording of `truth` under `conditions`, its random parts (targets, tremor, noise,
// jitter) from `seed`. See the header comment.
inline PreparedData family_recording(const DoorModel& truth, const RecordingConditions& conditions,
                                     std::uint32_t seed) {
  const RecordingConditions& c = conditions;
  if (c.hand != "pd" && c.hand != "minimum-jerk" && c.hand != "robot" && c.hand != "impulse") {
    throw std::invalid_argument("recording family: unknown hand '" + c.hand + "'");
  }
  if (c.sensors != "inclinometer+gyro" && c.sensors != "encoder" && c.sensors != "angle" &&
      c.sensors != "state") {
    throw std::invalid_argument("recording family: unknown sensors '" + c.sensors + "'");
  }
  if (c.strokes < 2 || !(c.sample_rate_hz >= 20.0) || !(c.jitter_fraction >= 0.0) ||
      c.jitter_fraction > 0.5) {
    throw std::invalid_argument(
        "recording family: needs strokes >= 2, sample_rate_hz >= 20 and jitter_fraction in [0, "
        "0.5]");
  }
  std::mt19937 random(seed);
  family_detail::Builder b(truth, c, random);
  b.run(family_detail::SegmentHand{}, family_detail::kRest_s, 0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int runs = (c.strokes + 1) / 2;
  for (int r = 0; r < runs; ++r) {
    // Targets spread over the range in rising rungs, each drawn within its rung.
    const double rung = (r + unit(random)) / runs;
    if (c.hand == "impulse") {
      family_detail::impulse_run(
          b, c.impulse_start_min_rad + rung * (c.impulse_start_max_rad - c.impulse_start_min_rad),
          2 * r + 1);
    } else {
      family_detail::grip_run(b, c.open_min_rad + rung * (c.open_max_rad - c.open_min_rad),
                              2 * r + 1);
    }
  }
  // Odd counts: drop the last closing's id.
  if (c.strokes % 2 == 1) std::replace(b.stroke.begin(), b.stroke.end(), c.strokes + 1, 0);
  // The data: the door as the hand moved it, sampled; or (replay_sampled_force) the door
  // again under the force as sampled (RecordedForce).
  Trajectory door;
  if (c.replay_sampled_force) {
    door = simulate(truth, RecordedForce(b.times, b.force), DoorState{}, b.times);
  } else {
    door.time_s = b.times;
    door.force_N = b.force;
    door.theta_rad = b.theta;
    door.omega_rad_s = b.omega;
  }
  if (c.sensors == "state") return family_detail::state_data(b, door, random);
  Recording recording = family_detail::sensor_recording(b, door, random);
  recording.source = "recording family seed " + std::to_string(seed);
  PreparedData data = prepare(recording);
  data.source = recording.source + ": " + c.describe();
  return data;
}

}  // namespace doorbench::testing
