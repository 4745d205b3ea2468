#include "haptic/tick_recorder.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "analysis/model/parameter_file.h"
#include "core/number_format.h"

namespace doorbench::haptic {
namespace {

constexpr std::size_t kBufferTicks = 4096;

// The channels, in the order of tick_value() below. The device's position, velocity and forces
// carry a Cartesian device's units here; a rotary device's are its own (channel_unit).
struct ChannelSpec {
  const char* name;
  const char* kind;
  const char* unit;
};
constexpr ChannelSpec kFixedChannels[] = {
    {"force", "haptic_force", "N"},  // the user's force along the arc: what a fit reads
    {"angle", "haptic_angle", "rad"},
    {"rate", "haptic_rate", "rad/s"},
    {"position_x", "haptic_position", "m"},
    {"position_y", "haptic_position", "m"},
    {"position_z", "haptic_position", "m"},
    {"velocity_x", "haptic_velocity", "m/s"},
    {"velocity_y", "haptic_velocity", "m/s"},
    {"velocity_z", "haptic_velocity", "m/s"},
    {"measured_force_x", "haptic_force_sensor", "N"},
    {"measured_force_y", "haptic_force_sensor", "N"},
    {"measured_force_z", "haptic_force_sensor", "N"},
    {"commanded_force_x", "haptic_command", "N"},
    {"commanded_force_y", "haptic_command", "N"},
    {"commanded_force_z", "haptic_command", "N"},
    {"model_torque", "haptic_model", "N*m"},
    {"passivity_torque", "haptic_safety", "N*m"},
    {"radial_error", "haptic_constraint", "m"},
    {"axial_error", "haptic_constraint", "m"},
    {"safety_scale", "haptic_safety", "1"},
    {"parameter_set", "haptic_parameters", "1"},
};
constexpr int kFixedCount = static_cast<int>(std::size(kFixedChannels));

double tick_value(const TickRecord& record, int channel) {
  switch (channel) {
    case 0:
      return record.user_force_N;
    case 1:
      return record.theta_rad;
    case 2:
      return record.omega_rad_s;
    case 3:
    case 4:
    case 5:
      return record.position[channel - 3];
    case 6:
    case 7:
    case 8:
      return record.velocity[channel - 6];
    case 9:
    case 10:
    case 11:
      return record.measured_force[channel - 9];
    case 12:
    case 13:
    case 14:
      return record.commanded_force[channel - 12];
    case 15:
      return record.model_torque_Nm;
    case 16:
      return record.passivity_torque_Nm;
    case 17:
      return record.radial_error_m;
    case 18:
      return record.axial_error_m;
    case 19:
      return record.safety_scale;
    case 20:
      return record.parameter_set;
    default:
      return record.terms_Nm[channel - kFixedCount];
  }
}

// A fixed channel's unit: the device's own for its position, velocity and forces.
std::string channel_unit(const ChannelSpec& spec, Kinematics kinematics) {
  const std::string_view kind = spec.kind;
  const DeviceUnits units = device_units(kinematics);
  if (kind == "haptic_position") return units.position;
  if (kind == "haptic_velocity") return units.velocity;
  if (kind == "haptic_force_sensor" || kind == "haptic_command") return units.force;
  return spec.unit;
}

ChannelInfo value_channel(const std::string& name, const std::string& kind,
                          const std::string& unit) {
  ChannelInfo info;
  info.name = name;
  info.sensor_kind = kind;
  info.raw_type = RawType::kValues;
  info.raw_unit = unit;
  info.unit = unit;
  info.sample_rate_hz = 0.0;                                  // explicit times: the ticks' own
  info.range_min = -std::numeric_limits<double>::infinity();  // unknown (session-format.md)
  info.range_max = std::numeric_limits<double>::infinity();
  return info;
}

}  // namespace

TickRecorder::TickRecorder(const std::filesystem::path& path, const SessionMetadata& metadata,
                           RenderLoop& loop, const DoorModel& model, const PlaybackSetup& setup)
    : path_(path), loop_(loop), setup_(setup) {
  writer_ = std::make_unique<SessionWriter>(path, metadata);
  term_count_ = model.term_count();
  const Kinematics kinematics = loop.mapping().kinematics();
  for (const ChannelSpec& spec : kFixedChannels) {
    channels_.push_back(
        {writer_->add_channel(value_channel(spec.name, spec.kind, channel_unit(spec, kinematics))),
         {}});
  }
  for (int term = 0; term < term_count_; ++term) {
    channels_.push_back(
        {writer_->add_channel(value_channel(std::string("term_").append(model.term_name(term)),
                                            "haptic_model", "N*m")),
         {}});
  }
  for (Channel& channel : channels_) channel.values.reserve(kBufferTicks);
  times_.reserve(kBufferTicks);
}

TickRecorder::~TickRecorder() {
  try {
    close();
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s: closing the haptic session failed: %s\n", path_.c_str(),
                 error.what());
  }
}

void TickRecorder::note_parameter_set(int id, const std::string& description,
                                      const DoorModel& model) {
  const std::lock_guard lock(mutex_);
  sets_.push_back({.id = id,
                   .description = description,
                   .parameters_json = to_parameter_json(model),
                   .effects_json = to_effects_json(model)});
}

void TickRecorder::add_event(const SessionEvent& event) {
  const std::lock_guard lock(mutex_);
  pending_events_.push_back(event);
}

void TickRecorder::flush_buffers() {
  if (times_.empty()) return;
  for (Channel& channel : channels_) {
    writer_->append_timed_values(channel.index, times_, channel.values);
    channel.values.clear();
  }
  times_.clear();
}

void TickRecorder::add_safety_events(const TickRecord& record, std::vector<SessionEvent>& events) {
  const bool same_reading =
      !std::isnan(previous_time_s_) && record.device_sequence == previous_sequence_;
  stale_ticks_ = same_reading ? stale_ticks_ + 1 : 0;
  EventFacts facts;
  facts.interval_s = record.time_s - previous_time_s_;
  facts.sample.position = record.position;
  facts.sample.velocity = record.velocity;
  facts.sample.sequence = record.device_sequence;
  facts.stale_ticks = stale_ticks_;
  previous_time_s_ = record.time_s;
  previous_sequence_ = record.device_sequence;
  for (std::uint32_t bit = 1; bit != 0 && bit <= record.events; bit <<= 1) {
    if ((record.events & bit) == 0) continue;
    std::string detail = loop_.safety().describe(bit, facts);
    if (bit == kEventLinkLost) {
      if (const std::string reason = loop_.device().stop_reason(); !reason.empty()) {
        detail = std::string(event_name(bit)).append(": ").append(reason);
      }
    }
    if ((bit & kTripEvents) != 0 && first_trip_.empty()) first_trip_ = detail;
    events.push_back(
        {.time_s = record.time_s, .kind = "safety", .channel = "", .detail = std::move(detail)});
  }
}

std::size_t TickRecorder::drain() {
  if (closed_) return 0;
  std::size_t count = 0;
  SpscRing<TickRecord>& ring = loop_.records();
  std::vector<SessionEvent> events;
  while (const TickRecord* record = ring.consumer_slot()) {
    times_.push_back(record->time_s);
    for (int channel = 0; channel < static_cast<int>(channels_.size()); ++channel) {
      channels_[channel].values.push_back(channel < kFixedCount ||
                                                  channel - kFixedCount < record->term_count
                                              ? tick_value(*record, channel)
                                              : 0.0);
    }
    if (record->parameter_set != last_parameter_set_) {
      std::string detail = "set " + std::to_string(record->parameter_set);
      {
        const std::lock_guard lock(mutex_);
        for (const KeptSet& set : sets_) {
          if (set.id == record->parameter_set) detail.append(": ").append(set.description);
        }
      }
      events.push_back(
          {.time_s = record->time_s, .kind = "parameters", .channel = "", .detail = detail});
      last_parameter_set_ = record->parameter_set;
    }
    add_safety_events(*record, events);
    ring.release();
    ++count;
    if (times_.size() >= kBufferTicks) flush_buffers();
  }
  flush_buffers();
  const std::lock_guard lock(mutex_);
  for (const SessionEvent& event : events) writer_->add_event(event);
  for (const SessionEvent& event : pending_events_) writer_->add_event(event);
  pending_events_.clear();
  ticks_written_.fetch_add(count, std::memory_order_relaxed);
  return count;
}

void TickRecorder::start(double interval_s) {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this, interval_s] {
    while (running_.load(std::memory_order_acquire)) {
      drain();
      std::this_thread::sleep_for(std::chrono::duration<double>(interval_s));
    }
  });
}

void TickRecorder::stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}

void TickRecorder::close() {
  if (closed_) return;
  stop();
  drain();
  const DoorMapping& mapping = loop_.mapping();
  const std::string group = "haptic";
  writer_->write_group_attribute(group, "device", setup_.device_name);
  writer_->write_group_attribute(group, "model_source", setup_.model_source);
  writer_->write_group_attribute(group, "effects", setup_.effects);
  writer_->write_group_attribute(group, "rate_hz", format_number(loop_.options().rate_hz));
  writer_->write_group_attribute(group, "handle_radius_m",
                                 format_number(mapping.handle_radius_m()));
  writer_->write_group_attribute(
      group, "kinematics",
      mapping.kinematics() == Kinematics::kCartesian3 ? "cartesian3" : "rotary1");
  if (mapping.kinematics() == Kinematics::kCartesian3) {
    const ArcGeometry& arc = mapping.geometry();
    auto vector_text = [](const Vec3& v) {
      return std::string("[")
          .append(format_number(v.x()))
          .append(", ")
          .append(format_number(v.y()))
          .append(", ")
          .append(format_number(v.z()))
          .append("]");
    };
    writer_->write_group_attribute(group, "arc_radius_m", format_number(arc.arc_radius_m));
    writer_->write_group_attribute(group, "hinge_point_m", vector_text(arc.hinge_point_m));
    writer_->write_group_attribute(group, "hinge_axis", vector_text(arc.hinge_axis));
    writer_->write_group_attribute(group, "closed_direction", vector_text(arc.closed_direction));
    writer_->write_group_attribute(group, "opening_direction", vector_text(arc.opening_direction));
  }
  const RenderLoopCounters counters = loop_.counters();
  writer_->write_group_attribute(group, "ticks", std::to_string(counters.ticks));
  writer_->write_group_attribute(group, "records_dropped",
                                 std::to_string(counters.records_dropped));
  writer_->write_group_attribute(group, "clipped_ticks", std::to_string(counters.clipped_ticks));
  writer_->write_group_attribute(group, "uses",
                                 "the render loop's ticks; tick times are CLOCK_MONOTONIC or "
                                 "simulated time from the session's start");
  {
    const std::lock_guard lock(mutex_);
    for (const KeptSet& set : sets_) {
      const std::string sets_group =
          std::string("haptic/parameter_sets/set_").append(std::to_string(set.id));
      writer_->write_group_attribute(sets_group, "description", set.description);
      writer_->write_group_attribute(sets_group, "parameters", set.parameters_json);
      writer_->write_group_attribute(sets_group, "effects", set.effects_json);
    }
  }
  closed_ = true;
  writer_->close();
}

}  // namespace doorbench::haptic
