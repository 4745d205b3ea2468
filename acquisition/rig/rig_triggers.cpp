// The rig file's triggers and recording (docs/rig-format.md, "Triggers" and
// "Recording"): each trigger with its level, the start and stop triggers named by the
// recording, and its limits.
#include <algorithm>
#include <cmath>

#include "acquisition/rig/internal/rig_toml.h"

namespace doorbench::rig_detail {

namespace {

constexpr std::string_view kTriggerKinds[] = {"software", "external", "level", "manual"};
constexpr std::string_view kDirections[] = {"rising", "falling"};
constexpr double kMaxPreTriggerS = 60.0;  // TriggerOptions::kMaxPreTriggerS
constexpr double kMaxHoldS = 3600.0;

// The level keys of a trigger, in the order they are checked.
constexpr std::string_view kLevelKeys[] = {"channel", "direction", "level", "hysteresis",
                                           "hold_s",  "absolute",  "unit"};

void read_level(const Section& table, const RigDefinition& rig, RigTrigger& trigger) {
  trigger.channel = table.required_string("channel");
  const RigChannel* channel = rig.find_channel(trigger.channel);
  if (channel == nullptr) {
    std::string names;
    for (const RigChannel& c : rig.channels) names.append(names.empty() ? "" : ", ").append(c.name);
    table.fail("channel", in_quotes(trigger.channel) + " is not a channel of the rig (they are " +
                              names + ")");
  }
  trigger.direction = table.choice("direction", kDirections, "a direction", "rising");
  const std::optional<double> level = table.number("level");
  if (!level)
    table.fail("level", "missing required key (in the channel's unit, " + channel->unit + ")");
  trigger.level = *level;
  trigger.hysteresis = table.number("hysteresis").value_or(0.0);
  if (trigger.hysteresis < 0) {
    table.fail("hysteresis", "must be >= 0 (got " + format_number(trigger.hysteresis) + ")");
  }
  trigger.hold_s = table.number("hold_s").value_or(0.0);
  if (!(trigger.hold_s >= 0 && trigger.hold_s <= kMaxHoldS)) {
    table.fail("hold_s", "must be from 0 to " + format_readable(kMaxHoldS) + " s (got " +
                             format_number(trigger.hold_s) + ")");
  }
  trigger.absolute = table.boolean("absolute").value_or(false);
  if (trigger.absolute && !(trigger.level > 0)) {
    table.fail("level",
               "must be > 0 for an absolute level (got " + format_number(trigger.level) + ")");
  }
  if (trigger.absolute && trigger.direction == "rising" && !(trigger.hysteresis < trigger.level)) {
    table.fail("hysteresis", "must be below level " + format_number(trigger.level) +
                                 " for an absolute rising level (got " +
                                 format_number(trigger.hysteresis) + ")");
  }
  if (const auto unit = table.string("unit"); unit && *unit != channel->unit) {
    table.fail("unit", in_quotes(*unit) + " is not the unit of channel " + channel->name +
                           ", which is " + in_quotes(channel->unit));
  }
}

// `name` must be a trigger's; its index.
std::size_t find_trigger(const Section& table, std::string_view key, const RigDefinition& rig,
                         const std::string& name) {
  for (std::size_t i = 0; i < rig.triggers.size(); ++i) {
    if (rig.triggers[i].name == name) return i;
  }
  std::string names;
  for (const RigTrigger& trigger : rig.triggers) {
    names.append(names.empty() ? "" : ", ").append(trigger.name);
  }
  table.fail(key, in_quotes(name) + " is not the name of a [[triggers]] table (" +
                      (names.empty() ? "there are none" : "they are " + names) + ")");
}

}  // namespace

std::vector<RigTrigger> read_triggers(const Section& root, const RigDefinition& rig) {
  std::vector<RigTrigger> triggers;
  for (const Section& table : root.array_of_tables("triggers")) {
    table.allow_only({"name", "kind", "source", "channel", "direction", "level", "hysteresis",
                      "hold_s", "absolute", "unit"});
    RigTrigger trigger;
    trigger.line = table.line();
    trigger.name = table.required_string("name");
    if (!is_name(trigger.name)) {
      table.fail("name", in_quotes(trigger.name) + " must consist of letters, digits and _ only");
    }
    if (trigger.name == "immediate") {
      table.fail("name", "\"immediate\" is reserved (recording.start = \"immediate\")");
    }
    for (std::size_t j = 0; j < triggers.size(); ++j) {
      if (triggers[j].name == trigger.name) {
        table.fail("name", in_quotes(trigger.name) + " is already the name of triggers[" +
                               std::to_string(j) + "] (line " + std::to_string(triggers[j].line) +
                               ")");
      }
    }
    trigger.kind = table.choice("kind", kTriggerKinds, "a trigger kind", std::nullopt);
    const std::optional<std::string> source = table.string("source");
    if (trigger.kind == "external" && !source) {
      table.fail("source",
                 "missing required key (an external trigger needs its input line, e.g. \"PFI0\")");
    }
    if (trigger.kind != "external" && source) {
      table.fail("source", "only external triggers have a source");
    }
    trigger.source = source.value_or("");
    if (trigger.kind == "level") {
      read_level(table, rig, trigger);
    } else {
      for (std::string_view key : kLevelKeys) {
        if (table.find(key)) table.fail(key, "only level triggers have a " + std::string(key));
      }
    }
    triggers.push_back(std::move(trigger));
  }
  return triggers;
}

void read_recording(const Section& root, RigDefinition& rig) {
  const std::optional<Section> table = root.table("recording");
  if (!table) return;
  table->allow_only({"start", "stop", "duration_s", "pre_trigger_s", "strokes", "min_stroke_s"});
  RigRecording& recording = rig.recording;
  recording.line = table->line();
  auto no_hold = [&](std::string_view key, const RigTrigger& trigger) {
    if (trigger.hold_s > 0) {
      table->fail(key, in_quotes(trigger.name) + " has hold_s (line " +
                           std::to_string(trigger.line) + "), which only a stop trigger uses");
    }
  };
  recording.start = table->string("start").value_or("immediate");
  const RigTrigger* start = nullptr;
  if (recording.start != "immediate") {
    start = &rig.triggers[find_trigger(*table, "start", rig, recording.start)];
    if (start->kind == "external" && rig.daq_start_trigger != start->name) {
      table->fail("start", in_quotes(start->name) +
                               " is an external trigger: it must also be daq.start_trigger, "
                               "so that the DAQ starts on its line");
    }
    if (start->kind == "level") no_hold("start", *start);
  }
  if (const auto stop = table->string("stop")) {
    const RigTrigger& trigger = rig.triggers[find_trigger(*table, "stop", rig, *stop)];
    if (trigger.kind != "level" && trigger.kind != "manual") {
      table->fail("stop", in_quotes(trigger.name) +
                              (trigger.kind == "external" ? " is an " : " is a ") + trigger.kind +
                              " trigger; a stop must be a level or manual trigger");
    }
    if (trigger.kind == "level" && start != nullptr && start->name == trigger.name) {
      table->fail("stop", in_quotes(trigger.name) +
                              " is also recording.start; a level stop needs a trigger of its own "
                              "(e.g. the falling edge)");
    }
    recording.stop = *stop;
  }
  if (const auto duration = table->number("duration_s")) {
    if (!(*duration > 0 && *duration <= kMaxRecordingS)) {
      table->fail("duration_s", "must be > 0 and <= " + format_readable(kMaxRecordingS) +
                                    " s (got " + format_number(*duration) + ")");
    }
    recording.duration_s = *duration;
  }
  recording.pre_trigger_s = table->number("pre_trigger_s").value_or(recording.pre_trigger_s);
  if (!(recording.pre_trigger_s >= 0 && recording.pre_trigger_s <= kMaxPreTriggerS)) {
    table->fail("pre_trigger_s", "must be from 0 to " + format_number(kMaxPreTriggerS) +
                                     " s (got " + format_number(recording.pre_trigger_s) + ")");
  }
  if (const auto strokes = table->string("strokes")) {
    const RigTrigger& trigger = rig.triggers[find_trigger(*table, "strokes", rig, *strokes)];
    if (trigger.kind != "level") {
      table->fail("strokes", in_quotes(trigger.name) +
                                 (trigger.kind == "external" ? " is an " : " is a ") +
                                 trigger.kind + " trigger; stroke markers need a level trigger");
    }
    no_hold("strokes", trigger);
    recording.strokes = *strokes;
  }
  recording.min_stroke_s = table->number("min_stroke_s").value_or(recording.min_stroke_s);
  if (!(recording.min_stroke_s >= 0 && recording.min_stroke_s <= kMaxRecordingS)) {
    table->fail("min_stroke_s", "must be from 0 to " + format_readable(kMaxRecordingS) +
                                    " s (got " + format_number(recording.min_stroke_s) + ")");
  }
}

void check_start_trigger(const Section& root, const RigDefinition& rig) {
  if (rig.daq_start_trigger.empty()) return;
  for (const RigTrigger& trigger : rig.triggers) {
    if (trigger.name == rig.daq_start_trigger) return;
  }
  std::string names;
  for (const RigTrigger& trigger : rig.triggers) {
    names.append(names.empty() ? "" : ", ").append(trigger.name);
  }
  root.table("daq")->fail("start_trigger",
                          in_quotes(rig.daq_start_trigger) + " is not the name of a [[triggers]] " +
                              "table (" + (names.empty() ? "there are none" : "they are " + names) +
                              ")");
}

}  // namespace doorbench::rig_detail
