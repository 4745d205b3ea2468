// The trigger's options (validated, and read from a rig file's triggers), the conversion
// of a channel's raw values to physical ones and the level detector, and the summary's
// report (trigger.h, docs/triggering.md). The stage itself is trigger.cpp.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "acquisition/record/trigger.h"
#include "acquisition/rig/rig_file.h"
#include "core/number_format.h"

namespace doorbench {
namespace {

bool finite_at_least(double value, double min) {
  return std::isfinite(value) && value >= min;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Options

std::string LevelCondition::validate(std::string_view what) const {
  const std::string name(what);
  if (channel.empty()) return name + ".channel must name a channel";
  if (!std::isfinite(level)) return name + ".level must be a finite number";
  if (!finite_at_least(hysteresis, 0)) {
    return name + ".hysteresis must be >= 0 (got " + format_number(hysteresis) + ")";
  }
  if (!finite_at_least(hold_s, 0)) {
    return name + ".hold_s must be >= 0 (got " + format_number(hold_s) + ")";
  }
  if (absolute && !(level > 0)) {
    return name + ".level must be > 0 for an absolute level (got " + format_number(level) + ")";
  }
  if (absolute && direction == Direction::kRising && !(hysteresis < level)) {
    return name + ".hysteresis " + format_number(hysteresis) + " must be below the level " +
           format_number(level) + " for an absolute rising level (|value| could never re-arm)";
  }
  return "";
}

std::string LevelCondition::describe(std::string_view unit) const {
  std::string text = absolute ? "|" + channel + "|" : channel;
  text.append(direction == Direction::kRising ? " > " : " < ").append(format_number(level));
  if (!unit.empty()) text.append(" ").append(unit);
  return text;
}

std::string TriggerOptions::validate() const {
  if (!(pre_trigger_s >= 0 && pre_trigger_s <= kMaxPreTriggerS)) {
    return "pre_trigger_s must be from 0 to " + format_number(kMaxPreTriggerS) + " s (got " +
           format_number(pre_trigger_s) + ")";
  }
  if (!finite_at_least(duration_s, 0)) {
    return "duration_s must be >= 0 (got " + format_number(duration_s) + ")";
  }
  if (!finite_at_least(min_stroke_s, 0)) {
    return "min_stroke_s must be >= 0 (got " + format_number(min_stroke_s) + ")";
  }
  if (!(max_poll_rate_hz > 0 && max_poll_rate_hz <= 1e6)) {
    return "max_poll_rate_hz must be > 0 and <= 1e6 (got " + format_number(max_poll_rate_hz) + ")";
  }
  if (!(lookahead_s >= 0 && lookahead_s <= kMaxPreTriggerS)) {
    return "lookahead_s must be from 0 to " + format_number(kMaxPreTriggerS) + " s (got " +
           format_number(lookahead_s) + ")";
  }
  if (start == Start::kLevel) {
    if (std::string problem = start_level.validate("start_level"); !problem.empty()) {
      return problem;
    }
  }
  if (start == Start::kExternal && external_source.empty()) {
    return "external_source must name the start line (e.g. \"PFI0\") for an external start";
  }
  if (start == Start::kManual && manual_start == nullptr) {
    return "manual_start must point to the flag that starts the recording";
  }
  if (stop == Stop::kLevel) {
    if (std::string problem = stop_level.validate("stop_level"); !problem.empty()) return problem;
  }
  if (stop == Stop::kManual && manual_stop == nullptr) {
    return "manual_stop must point to the flag that stops the recording";
  }
  if (start == Start::kManual && stop == Stop::kManual && manual_start == manual_stop) {
    return "manual_start and manual_stop must be different flags (the start's would stop at "
           "once)";
  }
  if (strokes) {
    if (std::string problem = strokes->validate("strokes"); !problem.empty()) return problem;
  }
  return "";
}

TriggerOptions trigger_options_from_rig(const RigDefinition& rig) {
  const RigRecording& recording = rig.recording;
  auto find = [&](const std::string& name) -> const RigTrigger& {
    for (const RigTrigger& trigger : rig.triggers) {
      if (trigger.name == name) return trigger;
    }
    throw std::invalid_argument(rig.source + ": recording names trigger \"" + name +
                                "\", which is not in the rig");
  };
  auto level_of = [](const RigTrigger& trigger) {
    LevelCondition condition;
    condition.channel = trigger.channel;
    condition.direction = trigger.direction == "falling" ? LevelCondition::Direction::kFalling
                                                         : LevelCondition::Direction::kRising;
    condition.level = trigger.level;
    condition.hysteresis = trigger.hysteresis;
    condition.hold_s = trigger.hold_s;
    condition.absolute = trigger.absolute;
    return condition;
  };

  TriggerOptions options;
  options.pre_trigger_s = recording.pre_trigger_s;
  options.duration_s = recording.duration_s;
  options.min_stroke_s = recording.min_stroke_s;
  if (recording.start == "immediate" && !rig.daq_start_trigger.empty()) {
    // The DAQ itself waits for its start line, so "at once" is at that line.
    const RigTrigger& daq_start = find(rig.daq_start_trigger);
    if (daq_start.kind == "external") {
      options.start = TriggerOptions::Start::kExternal;
      options.external_source = daq_start.source;
    }
  } else if (recording.start != "immediate") {
    const RigTrigger& start = find(recording.start);
    if (start.kind == "level") {
      options.start = TriggerOptions::Start::kLevel;
      options.start_level = level_of(start);
    } else if (start.kind == "manual") {
      options.start = TriggerOptions::Start::kManual;
    } else if (start.kind == "external") {
      options.start = TriggerOptions::Start::kExternal;
      options.external_source = start.source;
    }  // software: doorbench starts the DAQ, so the recording starts at once
  }
  if (!recording.stop.empty()) {
    const RigTrigger& stop = find(recording.stop);
    if (stop.kind == "level") {
      options.stop = TriggerOptions::Stop::kLevel;
      options.stop_level = level_of(stop);
    } else if (stop.kind == "manual") {
      options.stop = TriggerOptions::Stop::kManual;
    } else {
      throw std::invalid_argument(rig.source + ": recording.stop \"" + stop.name +
                                  "\" must be a level or manual trigger");
    }
  }
  if (!recording.strokes.empty()) options.strokes = level_of(find(recording.strokes));
  return options;
}

// ---------------------------------------------------------------------------------------
// Conversion and detection

PhysicalConverter::PhysicalConverter(const ChannelInfo& channel,
                                     std::span<const CalibrationRecord> records)
    : offset_(channel.raw_offset), scale_(channel.raw_scale) {
  if (channel.calibration_id.empty()) return;
  for (const CalibrationRecord& record : records) {
    if (record.id == channel.calibration_id) {
      coefficients_ = record.coefficients;
      return;
    }
  }
  throw std::invalid_argument("channel " + channel.name + ": its calibration record \"" +
                              channel.calibration_id + "\" is not among the session's records");
}

LevelDetector::LevelDetector(const LevelCondition& condition)
    : rising_(condition.direction == LevelCondition::Direction::kRising),
      absolute_(condition.absolute),
      level_(condition.level),
      hysteresis_(condition.hysteresis) {}

bool LevelDetector::fire(double value) {
  const double v = magnitude(value);
  if (armed_ && (rising_ ? v >= level_ : v <= level_)) {
    armed_ = false;
    return true;
  }
  if (!armed_ && released(value)) armed_ = true;
  return false;
}

bool LevelDetector::released(double value) const {
  const double v = magnitude(value);
  return rising_ ? v < level_ - hysteresis_ : v > level_ + hysteresis_;
}

bool LevelDetector::on_fired_side(double value) const {
  return !released(value);
}

std::string TriggerSummary::brief_report() const {
  char text[400];
  std::snprintf(
      text, sizeof text,
      "trigger %s: triggered at %.6g s, stopped at %.6g s; %llu scans from scan %llu, "
      "%llu polled samples, %llu events, %llu strokes forwarded; %llu polled and %llu "
      "event pre-trigger slots overwritten; buffers %.3g MB",
      state.c_str(), trigger_time_s, stop_time_s, static_cast<unsigned long long>(forwarded_scans),
      static_cast<unsigned long long>(first_forwarded_scan),
      static_cast<unsigned long long>(forwarded_timed_samples),
      static_cast<unsigned long long>(forwarded_events), static_cast<unsigned long long>(strokes),
      static_cast<unsigned long long>(timed_overwritten),
      static_cast<unsigned long long>(events_overwritten), static_cast<double>(buffer_bytes) / 1e6);
  return text;
}

}  // namespace doorbench
