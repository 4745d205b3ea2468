#pragma once
// The simulated bench: a door model (any model plus effects) opened and closed by the
// virtual hand, its truth (θ, ω, the hand's force) turned into raw DAQ counts by the
// sensor models of the rig's channels. Seeded: the same rig and seed give the same
// session. Paced in real time or as fast as possible ([simulation] realtime).
//
// The load cell measures compression only (door-models.md §5): during openings it sits
// between the hand and the inside of the handle and is pressed by +F_u; during closings
// it is on the door's outer face and is pressed by −F_u. Each stroke_start event says
// which ("opening" or "closing"), so F_u = ± the reading.
//
// The truth is kept in memory (32 bytes per scan) and written to the session's "truth"
// group when recording ends. Thread safety: one thread.
#include <chrono>
#include <memory>
#include <random>
#include <variant>
#include <vector>

#include "acquisition/record/backend.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/recording_csv.h"
#include "analysis/model/door_model.h"
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"
#include "sensors/rig_recording.h"
#include "sensors/sensor_models.h"

namespace doorbench::simulated_bench {

// A force at the handle that also knows its strokes, so the bench can mark them and
// mount the compression-only load cell the right way round.
class StrokeForce : public UserForce {
 public:
  // 0 between strokes; otherwise an id that differs from the previous stroke's.
  virtual int stroke_at(double time_s) const = 0;
  // During a stroke: +1 if it is an opening (the cell is pressed by +F_u), −1 a closing.
  virtual int mounting_at(double time_s) const = 0;
  virtual double natural_duration_s() const = 0;  // how long it has something to do
  // The bench calls this when a stroke starts, with the door's angle then (a person sees
  // where the door is before pushing it).
  virtual void stroke_started(double /*time_s*/, double /*theta_rad*/) {}
};

// The virtual hand's open-close repeated `cycles` times, then no force.
//
// push_only: the hand acts on the door through a compression-only load cell (the bench's
// mounting), so it can push the cell but never pull it: during an opening its force is
// max(F, 0), during a closing min(F, 0). Where the tracking controller would brake the
// door (a door that falls open, the end of a fast stroke) it lets go instead, as a person
// pushing a handle through the cell must. Without this, the cell would read 0 while the
// door felt a pull, and the recorded force would not be the force that moved the door.
// A push-only hand plans each closing from where the door is when the closing starts
// (the door may have run past the target).
class CyclingHand final : public StrokeForce {
 public:
  CyclingHand(const VirtualHandOptions& one_cycle, double handle_radius_m, int cycles,
              bool push_only = false);
  double force_N(double time_s, double theta_rad, double omega_rad_s) const override;
  int stroke_at(double time_s) const override;  // 1 opening, 2 closing, 0 between
  int mounting_at(double time_s) const override { return stroke_at(time_s) == 2 ? -1 : 1; }
  // The cycles and then kFinalRestS at rest, so that the recording ends on a still
  // period (preprocessing anchors the last closing's angle to it).
  double natural_duration_s() const override { return cycles_ * period_s() + kFinalRestS; }
  static constexpr double kFinalRestS = 1.0;
  double period_s() const { return hand_.duration_s(); }
  void stroke_started(double time_s, double theta_rad) override;

 private:
  VirtualHand hand_;
  int cycles_;
  bool push_only_;
  double closing_from_rad_;
};

// A scripted force: a recording's force_N (linearly interpolated) and its strokes; each
// stroke is an opening if its mean force is positive, else a closing.
class ScriptedForce final : public StrokeForce {
 public:
  explicit ScriptedForce(const Recording& recording);  // needs a stroke column
  double force_N(double time_s, double theta_rad, double omega_rad_s) const override;
  int stroke_at(double time_s) const override;
  int mounting_at(double time_s) const override;
  double natural_duration_s() const override { return time_s_.back(); }

 private:
  std::size_t sample_at(double time_s) const;  // the last sample at or before time_s
  RecordedForce force_;
  std::vector<double> time_s_;
  std::vector<int> stroke_;
  std::vector<int> mounting_;  // per sample, from its stroke's mean force
};

// The force a rig's [simulation] table names: its scripted force file, or the virtual hand
// (push-only when the rig's load cell is compression-only).
std::unique_ptr<StrokeForce> simulated_hand(const RigDefinition& rig, const DoorModel& model);

// The door model a rig's [simulation] table names (the built-in reference door, or a
// parameter file relative to the rig, with an optional effects file).
DoorModel simulated_door_model(const RigDefinition& rig);

class SimulatedBench final : public AcquisitionBackend {
 public:
  // Every channel of the rig must use the simulated backend. `expected_duration_s`
  // sizes the truth buffers so that reading does not allocate. `model` must outlive it.
  SimulatedBench(const RigDefinition& rig, const DoorModel& model, double expected_duration_s);
  // The same with the force already built (simulated_hand(rig, model)).
  SimulatedBench(const RigDefinition& rig, const DoorModel& model,
                 std::unique_ptr<StrokeForce> hand, double expected_duration_s);

  std::string description() const override;
  std::vector<ChannelInfo> channels() const override { return channels_; }
  std::vector<CalibrationRecord> calibrations() const override { return calibrations_; }
  double scan_rate_hz() const override { return scan_rate_hz_; }
  void start() override;
  std::size_t read(ScanBlock& block) override;
  void stop() override {}
  void write_extras(SessionWriter& writer, double session_origin_s) override;

 private:
  using Sensor = std::variant<sensors::LoadCell, sensors::Inclinometer, sensors::Gyroscope>;
  struct Channel {
    Sensor sensor;
    sensors::Daq daq;
  };

  std::string rig_name_;
  std::string door_json_, effects_json_;
  const DoorModel& model_;
  RigSimulation simulation_;
  double scan_rate_hz_;
  double convert_interval_s_;
  std::vector<ChannelInfo> channels_;
  std::vector<CalibrationRecord> calibrations_;
  std::vector<Channel> sensors_;
  std::unique_ptr<StrokeForce> hand_;
  DoorStepper stepper_;
  DoorState state_;
  std::size_t next_scan_ = 0;
  int previous_stroke_ = 0;
  int mounting_sign_ = 1;  // +1: the load cell is pressed by +F_u (opening mounting)
  std::chrono::steady_clock::time_point started_;
  std::vector<double> truth_time_s_, truth_theta_rad_, truth_omega_rad_s_, truth_force_N_;
};

// The simulated bench for a recording of `rig` (sensors/rig_recording.h): its door model and
// hand, playing `duration_s` (0: the hand's cycles), paced when the rig's [simulation]
// table asks for real time. Every channel of the rig must use the simulated backend.
sensors::SimulatedScans simulated_scans(const RigDefinition& rig, double duration_s);

}  // namespace doorbench::simulated_bench
