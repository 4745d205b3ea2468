#include "simulated_bench/simulated_bench.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <thread>

#include "analysis/model/parameter_file.h"
#include "core/number_format.h"
#include "core/units.h"
#include "sensors/rig_channel.h"

namespace doorbench::simulated_bench {

using sensors::counts_channel_info;
using sensors::Daq;
using sensors::Gyroscope;
using sensors::Inclinometer;
using sensors::LoadCell;
using sensors::parameters_of;
using sensors::rig_channel_calibration;

namespace {

VirtualHandOptions hand_options(const RigSimulation& simulation) {
  VirtualHandOptions options;
  options.target_angle_rad = simulation.hand_target_deg * kRadPerDeg;
  options.duration_s = simulation.hand_cycle_duration_s;
  return options;
}

}  // namespace

CyclingHand::CyclingHand(const VirtualHandOptions& one_cycle, double handle_radius_m, int cycles,
                         bool push_only)
    : hand_(one_cycle, handle_radius_m),
      cycles_(cycles),
      push_only_(push_only),
      closing_from_rad_(one_cycle.target_angle_rad) {
  if (cycles < 1) throw std::invalid_argument("the virtual hand needs at least one cycle");
}

double CyclingHand::force_N(double time_s, double theta_rad, double omega_rad_s) const {
  if (time_s < 0 || time_s >= cycles_ * period_s()) return 0.0;
  const double force =
      hand_.force_N(std::fmod(time_s, period_s()), theta_rad, omega_rad_s, closing_from_rad_);
  if (!push_only_) return force;
  return mounting_at(time_s) * force > 0.0 ? force : 0.0;
}

void CyclingHand::stroke_started(double time_s, double theta_rad) {
  if (push_only_ && stroke_at(time_s) == 2) closing_from_rad_ = std::max(theta_rad, 0.0);
}

int CyclingHand::stroke_at(double time_s) const {
  if (time_s < 0 || time_s >= cycles_ * period_s()) return 0;
  return hand_.stroke_at(std::fmod(time_s, period_s()));
}

ScriptedForce::ScriptedForce(const Recording& recording)
    : force_(recording.time_s, recording.force_N), time_s_(recording.time_s) {
  if (!recording.stroke) {
    throw std::invalid_argument(recording.source +
                                ": a scripted force needs a stroke column (the load cell's "
                                "mounting follows the strokes)");
  }
  stroke_ = *recording.stroke;
  // Each stroke's mounting from the sign of its mean force.
  std::map<int, double> force_sum;
  for (std::size_t i = 0; i < stroke_.size(); ++i) force_sum[stroke_[i]] += recording.force_N[i];
  mounting_.resize(stroke_.size());
  for (std::size_t i = 0; i < stroke_.size(); ++i) {
    mounting_[i] = force_sum[stroke_[i]] >= 0 ? 1 : -1;
  }
}

std::size_t ScriptedForce::sample_at(double time_s) const {
  const auto after = std::upper_bound(time_s_.begin(), time_s_.end(), time_s);
  return after == time_s_.begin() ? 0 : static_cast<std::size_t>(after - time_s_.begin()) - 1;
}

double ScriptedForce::force_N(double time_s, double theta_rad, double omega_rad_s) const {
  return force_.force_N(time_s, theta_rad, omega_rad_s);
}

int ScriptedForce::stroke_at(double time_s) const {
  if (time_s < time_s_.front() || time_s > time_s_.back()) return 0;
  return stroke_[sample_at(time_s)];
}

int ScriptedForce::mounting_at(double time_s) const {
  return mounting_[sample_at(time_s)];
}

std::unique_ptr<StrokeForce> simulated_hand(const RigDefinition& rig, const DoorModel& model) {
  if (!rig.simulation) throw std::invalid_argument(rig.source + ": no [simulation] table");
  if (!rig.simulation->force.empty()) {
    return std::make_unique<ScriptedForce>(read_recording_csv(rig.resolve(rig.simulation->force)));
  }
  const bool compression_only_cell =
      std::any_of(rig.channels.begin(), rig.channels.end(), [](const RigChannel& channel) {
        return channel.sensor == "load_cell" &&
               parameters_of<LoadCellParameters>(channel).compression_only != 0;
      });
  return std::make_unique<CyclingHand>(hand_options(*rig.simulation),
                                       model.geometry().handle_radius_m,
                                       rig.simulation->hand_cycles, compression_only_cell);
}

DoorModel simulated_door_model(const RigDefinition& rig) {
  if (!rig.simulation) throw std::invalid_argument(rig.source + ": no [simulation] table");
  const RigSimulation& simulation = *rig.simulation;
  const std::optional<ModelKind> kind = parse_model_kind(simulation.model);
  if (!kind)
    throw std::invalid_argument(rig.source + ": simulation.model must be sensory or physical");
  const std::filesystem::path params =
      simulation.door == "reference" ? std::filesystem::path() : rig.resolve(simulation.door);
  const std::filesystem::path effects =
      simulation.effects.empty() ? std::filesystem::path() : rig.resolve(simulation.effects);
  return load_model(*kind, params, effects);
}

SimulatedBench::SimulatedBench(const RigDefinition& rig, const DoorModel& model,
                               double expected_duration_s)
    : SimulatedBench(rig, model, simulated_hand(rig, model), expected_duration_s) {}

SimulatedBench::SimulatedBench(const RigDefinition& rig, const DoorModel& model,
                               std::unique_ptr<StrokeForce> hand, double expected_duration_s)
    : rig_name_(rig.name),
      door_json_(to_parameter_json(model)),
      effects_json_(to_effects_json(model)),
      model_(model),
      simulation_(rig.simulation ? *rig.simulation : RigSimulation{}),
      scan_rate_hz_(rig.sample_rate_hz),
      convert_interval_s_(rig.convert_interval_s),
      hand_(std::move(hand)),
      stepper_(model, SimulationOptions{}) {
  if (!rig.simulation) throw std::invalid_argument(rig.source + ": no [simulation] table");
  if (!hand_) throw std::invalid_argument("the simulated bench needs a force at the handle");
  for (std::size_t index = 0; index < rig.channels.size(); ++index) {
    const RigChannel& rc = rig.channels[index];
    if (rc.backend != "simulated") {
      throw std::invalid_argument(rig.source + ": channel " + rc.name + " uses backend " +
                                  rc.backend + "; the simulated bench simulates every channel");
    }
    DaqParameters daq_parameters;
    daq_parameters.range_min_V = rc.range_min_V;
    daq_parameters.range_max_V = rc.range_max_V;
    daq_parameters.resolution_bits = rig.daq_resolution_bits;
    daq_parameters.sample_rate_hz = rig.sample_rate_hz;
    daq_parameters.convert_interval_s = rig.convert_interval_s;
    const Daq daq(daq_parameters);
    // One seed per channel, derived from the rig's: channels' noises are independent.
    const std::uint64_t seed = simulation_.seed * 1000003u + index;
    if (rc.sensor == "load_cell") {
      sensors_.push_back({LoadCell(parameters_of<LoadCellParameters>(rc), seed), daq});
    } else if (rc.sensor == "inclinometer") {
      sensors_.push_back(
          {Inclinometer(parameters_of<InclinometerParameters>(rc), scan_rate_hz_, seed), daq});
    } else if (rc.sensor == "gyroscope") {
      sensors_.push_back(
          {Gyroscope(parameters_of<GyroscopeParameters>(rc), scan_rate_hz_, seed), daq});
    } else {
      throw std::invalid_argument("channel " + rc.name + ": no sensor model for " + rc.sensor);
    }
    const CalibrationRecord record = rig_channel_calibration(rig, rc);
    calibrations_.push_back(record);
    channels_.push_back(counts_channel_info(
        rc, record,
        {.raw_offset_V = rc.range_min_V,
         .raw_scale_V = daq.volts_per_count(),
         .range_min_V = rc.range_min_V,
         .range_max_V = rc.range_max_V,
         .sample_rate_hz = scan_rate_hz_,
         .first_sample_time_s = daq.channel_time_offset_s(static_cast<int>(index))}));
  }
  const auto scans = static_cast<std::size_t>(std::ceil(expected_duration_s * scan_rate_hz_)) + 1;
  for (auto* truth : {&truth_time_s_, &truth_theta_rad_, &truth_omega_rad_s_, &truth_force_N_}) {
    truth->reserve(scans);
  }
}

std::string SimulatedBench::description() const {
  return "simulated bench (" + rig_name_ + ", " + std::string(to_string(model_.kind())) +
         " model, seed " + std::to_string(simulation_.seed) + ")";
}

void SimulatedBench::start() {
  state_ = DoorState{};
  for (Channel& channel : sensors_) {
    if (auto* inclinometer = std::get_if<Inclinometer>(&channel.sensor)) inclinometer->settle(0.0);
  }
  started_ = std::chrono::steady_clock::now();
  next_scan_ = 0;
}

std::size_t SimulatedBench::read(ScanBlock& block) {
  const std::size_t scans = block.capacity();
  for (std::size_t s = 0; s < scans; ++s) {
    const double scan_time_s = static_cast<double>(next_scan_) / scan_rate_hz_;
    if (next_scan_ == 0) {
      block.events.push_back(
          {.time_s = 0.0, .kind = "trigger", .channel = "", .detail = "start (software)"});
    }
    // Strokes begin and end with the hand's phases; the load cell's mounting follows.
    const int stroke = hand_->stroke_at(scan_time_s);
    if (stroke != previous_stroke_) {
      if (previous_stroke_ != 0) {
        block.events.push_back(
            {.time_s = scan_time_s, .kind = "stroke_end", .channel = "", .detail = ""});
      }
      if (stroke != 0) {
        mounting_sign_ = hand_->mounting_at(scan_time_s);
        hand_->stroke_started(scan_time_s, state_.theta_rad);
        block.events.push_back({.time_s = scan_time_s,
                                .kind = "stroke_start",
                                .channel = "",
                                .detail = mounting_sign_ > 0 ? "opening" : "closing"});
      }
      previous_stroke_ = stroke;
    }
    for (std::size_t c = 0; c < sensors_.size(); ++c) {
      const double convert_time_s = scan_time_s + c * convert_interval_s_;
      stepper_.advance(state_, convert_time_s, *hand_);
      if (c == 0) {
        truth_time_s_.push_back(scan_time_s);
        truth_theta_rad_.push_back(state_.theta_rad);
        truth_omega_rad_s_.push_back(state_.omega_rad_s);
        truth_force_N_.push_back(
            hand_->force_N(state_.time_s, state_.theta_rad, state_.omega_rad_s));
      }
      Channel& channel = sensors_[c];
      double volts = 0.0;
      if (auto* load_cell = std::get_if<LoadCell>(&channel.sensor)) {
        const double hand_force_N =
            hand_->force_N(state_.time_s, state_.theta_rad, state_.omega_rad_s);
        volts = load_cell->sample_V(mounting_sign_ * hand_force_N);
      } else if (auto* inclinometer = std::get_if<Inclinometer>(&channel.sensor)) {
        volts = inclinometer->sample_V(state_.theta_rad);
      } else if (auto* gyroscope = std::get_if<Gyroscope>(&channel.sensor)) {
        volts = gyroscope->sample_V(state_.omega_rad_s);
      }
      block.counts[c][s] = channel.daq.to_counts(volts);
    }
    ++next_scan_;
  }
  block.scan_count = scans;
  if (simulation_.realtime) {
    const auto due = started_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(next_scan_ / scan_rate_hz_));
    std::this_thread::sleep_until(due);
  }
  return scans;
}

void SimulatedBench::write_extras(SessionWriter& writer, double session_origin_s) {
  const std::string group = "truth";
  writer.write_group_attribute(group, "about",
                               "noise-free truth of the simulated bench at each scan's start: "
                               "door angle and rate, and the hand's force F_u at the handle "
                               "(positive = opening)");
  writer.write_group_attribute(group, "model", std::string(to_string(model_.kind())));
  writer.write_group_attribute(group, "door_parameters_json", door_json_);
  writer.write_group_attribute(group, "effects_json", effects_json_);
  writer.write_group_attribute(group, "seed", std::to_string(simulation_.seed));
  writer.write_group_attribute(group, "handle_radius_m",
                               format_number(model_.geometry().handle_radius_m));
  // On the session's clock (a trigger may have moved its origin).
  std::vector<double> time_s = truth_time_s_;
  for (double& t : time_s) t -= session_origin_s;
  writer.write_group_dataset(group, "time_s", time_s);
  writer.write_group_dataset(group, "theta_rad", truth_theta_rad_);
  writer.write_group_dataset(group, "omega_rad_s", truth_omega_rad_s_);
  writer.write_group_dataset(group, "force_N", truth_force_N_);
}

sensors::SimulatedScans simulated_scans(const RigDefinition& rig, double duration_s) {
  // The bench keeps a reference to its door model: both live in one block, the backend
  // pointing into it.
  struct Bench {
    DoorModel model;
    std::optional<SimulatedBench> bench;
  };
  auto bench = std::make_shared<Bench>(Bench{simulated_door_model(rig), std::nullopt});
  std::unique_ptr<StrokeForce> hand = simulated_hand(rig, bench->model);
  sensors::SimulatedScans scans;
  scans.duration_s = duration_s > 0 ? duration_s : hand->natural_duration_s();
  bench->bench.emplace(rig, bench->model, std::move(hand), scans.duration_s);
  scans.backend = std::shared_ptr<AcquisitionBackend>(bench, &*bench->bench);
  scans.paced = rig.simulation && rig.simulation->realtime;
  return scans;
}

}  // namespace doorbench::simulated_bench
