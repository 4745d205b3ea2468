#include "study/tuning_keys.h"

#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "analysis/model/parameter_file.h"
#include "core/number_format.h"

namespace doorbench::study {
namespace {

using perceptual::Control;

constexpr TuningKey kKeys[] = {
    {.key = '+', .control = Control::kHeaviness, .increase = true, .action = "heavier"},
    {.key = '-', .control = Control::kHeaviness, .increase = false, .action = "lighter"},
    {.key = 'U', .control = Control::kLatchEffort, .increase = true, .action = "harder to unlatch"},
    {.key = 'u',
     .control = Control::kLatchEffort,
     .increase = false,
     .action = "easier to unlatch"},
    {.key = 'C', .control = Control::kClosingEffort, .increase = true, .action = "harder to close"},
    {.key = 'c',
     .control = Control::kClosingEffort,
     .increase = false,
     .action = "easier to close"},
    {.key = 'S', .control = Control::kSmoothness, .increase = true, .action = "rougher"},
    {.key = 's', .control = Control::kSmoothness, .increase = false, .action = "smoother"},
    {.key = 'N', .control = Control::kSnap, .increase = true, .action = "more snap"},
    {.key = 'n', .control = Control::kSnap, .increase = false, .action = "less snap"},
};

// Four significant digits: enough to tell steps of 10 % apart on an operator's screen.
std::string short_number(double value) {
  std::ostringstream text;
  text << std::setprecision(4) << value;
  return text.str();
}

const perceptual::ControlInfo& info_of(Control control) {
  for (const perceptual::ControlInfo& info : perceptual::controls()) {
    if (info.control == control) return info;
  }
  throw std::logic_error("tuning: control missing from perceptual::controls()");
}

std::string key_list() {
  std::string text;
  for (const TuningKey& key : kKeys) text.append(1, key.key).append(" ");
  return text.append(1, kResetKey);
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

}  // namespace

std::span<const TuningKey> tuning_keys() {
  return kKeys;
}

std::string key_map_text() {
  std::string text;
  for (const TuningKey& key : kKeys) {
    const perceptual::ControlInfo& info = info_of(key.control);
    text.append("  ")
        .append(1, key.key)
        .append("  ")
        .append(key.action)
        .append(": ")
        .append(info.name)
        .append(key.increase ? " x step\n" : " / step\n");
  }
  return text.append("  r  reset to the starting parameter set\n");
}

std::string KeyOptions::validate() const {
  if (!std::isfinite(step_factor) || step_factor <= 1.0 || step_factor > 2.0) {
    return "step factor must be above 1 and at most 2, got " + format_number(step_factor);
  }
  return "";
}

KeyOutcome apply_key(const DoorModel& model, char key, const KeyOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("tuning options: " + problem);
  }
  KeyOutcome outcome;
  const TuningKey* found = nullptr;
  for (const TuningKey& candidate : kKeys) {
    if (candidate.key == key) found = &candidate;
  }
  if (found == nullptr) {
    outcome.action = "unknown";
    outcome.message =
        std::string("key '").append(1, key).append("' does nothing (keys: ") + key_list() + ")";
    return outcome;
  }
  const perceptual::ControlInfo& info = info_of(found->control);
  outcome.action = std::string(found->action);
  outcome.control = std::string(info.name);
  outcome.unit = std::string(info.unit);
  const std::string refused = outcome.action + " refused: ";
  if (model.kind() != ModelKind::kSensory) {
    outcome.message = refused + "the perceptual controls act on the sensory model only";
    return outcome;
  }
  const double old_value = perceptual::read(model, found->control);
  const double new_value =
      found->increase ? old_value * options.step_factor : old_value / options.step_factor;
  outcome.old_value = old_value;
  outcome.new_value = new_value;
  if (old_value == 0.0) {
    outcome.message = refused + outcome.control + " is 0 " + outcome.unit +
                      ", and a step multiplies it, so it cannot move from 0";
    return outcome;
  }
  std::optional<DoorModel> changed;
  try {
    changed = perceptual::set(model, found->control, new_value);
  } catch (const std::invalid_argument& error) {
    outcome.message = refused + outcome.control + " " + short_number(new_value) + " " +
                      outcome.unit + ": " + error.what();
    return outcome;
  }
  // The parameter set's bounds: the model does not enforce them, tuning does. Every control
  // is linear in the parameters it sets, so the control's own limit follows from the bound.
  std::string violation;
  double nearest_limit = 0.0;
  bool have_limit = false;
  for (int i = 0; i < changed->parameter_count(); ++i) {
    const double before = model.parameter_values()[i];
    const double after = changed->parameter_values()[i];
    const Bounds bounds = changed->parameter_bounds()[i];
    const bool below = after < bounds.lower;
    const bool above = after > bounds.upper;
    if (!below && !above) continue;
    const double bound = below ? bounds.lower : bounds.upper;
    if (violation.empty()) {
      violation = changed->parameter_name(i) + " would be " + short_number(after) + ", " +
                  (below ? "below its lower" : "above its upper") + " bound " + short_number(bound);
    }
    if (after != before) {
      const double limit =
          old_value + (bound - before) * (new_value - old_value) / (after - before);
      if (!have_limit || std::abs(limit - old_value) < std::abs(nearest_limit - old_value)) {
        nearest_limit = limit;
        have_limit = true;
      }
    }
  }
  if (!violation.empty()) {
    outcome.message = refused + outcome.control + " " + short_number(new_value) + " " +
                      outcome.unit + " is out of bounds: " + violation;
    if (have_limit) {
      outcome.message += "; the limit of " + outcome.control + " is " +
                         short_number(nearest_limit) + " " + outcome.unit;
    }
    return outcome;
  }
  outcome.model = std::move(changed);
  outcome.message = outcome.action + ": " + outcome.control + " " + short_number(old_value) +
                    " -> " + short_number(new_value) + " " + outcome.unit;
  return outcome;
}

std::string TuningLog::to_csv() const {
  std::string text = "time_s,key,action,control,old,new,unit,applied,parameter_set,message\n";
  for (const TuningLogEntry& e : entries_) {
    text.append(format_number(e.time_s))
        .append(",")
        .append(csv_field(std::string(1, e.key)))
        .append(",")
        .append(csv_field(e.action))
        .append(",")
        .append(csv_field(e.control))
        .append(",")
        .append(format_number(e.old_value))
        .append(",")
        .append(format_number(e.new_value))
        .append(",")
        .append(csv_field(e.unit))
        .append(",")
        .append(e.applied ? "1" : "0")
        .append(",")
        .append(csv_field(e.parameter_set_id))
        .append(",")
        .append(csv_field(e.message))
        .append("\n");
  }
  return text;
}

void TuningLog::write_to_session(SessionWriter& writer) const {
  for (const TuningLogEntry& e : entries_) {
    writer.add_event({.time_s = e.time_s,
                      .kind = "tuning",
                      .channel = "",
                      .detail = std::string("key ").append(1, e.key).append(": ") + e.message +
                                (e.applied ? " (set " + e.parameter_set_id + ")" : "")});
  }
  writer.write_group_attribute("tuning", "log_csv", to_csv());
}

KeyTuner::KeyTuner(DoorModel start, std::string base_id, const KeyOptions& options)
    : start_(start),
      current_(std::move(start)),
      base_id_(std::move(base_id)),
      current_id_(base_id_),
      options_(options) {
  if (const std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument("tuning options: " + problem);
  }
  if (start_.kind() != ModelKind::kSensory) {
    throw std::invalid_argument("tuning: the perceptual controls act on the sensory model only");
  }
}

const TuningLogEntry& KeyTuner::press(char key, double time_s) {
  TuningLogEntry entry;
  entry.time_s = time_s;
  entry.key = key;
  if (key == kResetKey) {
    entry.action = "reset";
    entry.applied = true;
    entry.message = "reset: back to parameter set " + base_id_;
    current_ = start_;
    current_id_ = base_id_;
  } else {
    KeyOutcome outcome = apply_key(current_, key, options_);
    entry.action = outcome.action;
    entry.control = outcome.control;
    entry.unit = outcome.unit;
    entry.old_value = outcome.old_value;
    entry.new_value = outcome.new_value;
    entry.message = outcome.message;
    if (outcome.model) {
      entry.applied = true;
      current_ = std::move(*outcome.model);
      current_id_ = base_id_ + "-" + std::to_string(++changes_);
    }
  }
  entry.parameter_set_id = current_id_;
  log_.record(std::move(entry));
  return log_.entries().back();
}

void KeyTuner::write_to_session(SessionWriter& writer) const {
  log_.write_to_session(writer);
  writer.write_group_attribute("tuning", "start_parameters_json", to_parameter_json(start_));
  writer.write_group_attribute("tuning", "final_parameters_json", to_parameter_json(current_));
  writer.write_group_attribute("tuning", "final_parameter_set", current_id_);
}

TerminalKeys::TerminalKeys(int fd, const std::string& name) : fd_(fd), name_(name) {
  termios settings{};
  if (::isatty(fd) != 1 || ::tcgetattr(fd, &settings) != 0) {
    throw std::runtime_error(name_ +
                             " is not a terminal: live tuning keys need one (a keypad or "
                             "keyboard on the operator's console)");
  }
  saved_.resize(sizeof settings);
  std::memcpy(saved_.data(), &settings, sizeof settings);
  // Each key as it is pressed, not echoed; Ctrl-C still interrupts (ISIG kept).
  settings.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);
  settings.c_cc[VMIN] = 0;
  settings.c_cc[VTIME] = 0;
  if (::tcsetattr(fd, TCSANOW, &settings) != 0) {
    throw std::runtime_error(name_ + ": cannot set the terminal's mode: " + std::strerror(errno));
  }
}

TerminalKeys::~TerminalKeys() {
  termios settings{};
  std::memcpy(&settings, saved_.data(), sizeof settings);
  ::tcsetattr(fd_, TCSANOW, &settings);
}

std::optional<char> TerminalKeys::poll(double timeout_s) {
  pollfd request{fd_, POLLIN, 0};
  const int timeout_ms =
      timeout_s <= 0 ? 0 : static_cast<int>(std::ceil(std::min(timeout_s, 3600.0) * 1000.0));
  const int ready = ::poll(&request, 1, timeout_ms);
  if (ready < 0) {
    if (errno == EINTR) return std::nullopt;
    throw std::runtime_error(name_ + ": cannot wait for a key: " + std::strerror(errno));
  }
  if (ready == 0) return std::nullopt;
  if ((request.revents & POLLIN) == 0) {
    throw std::runtime_error(name_ + ": the terminal is gone (hung up)");
  }
  char key = 0;
  const ssize_t got = ::read(fd_, &key, 1);
  if (got == 1) return key;
  if (got == 0) throw std::runtime_error(name_ + ": end of input");
  if (errno == EINTR || errno == EAGAIN) return std::nullopt;
  throw std::runtime_error(name_ + ": cannot read a key: " + std::strerror(errno));
}

}  // namespace doorbench::study
