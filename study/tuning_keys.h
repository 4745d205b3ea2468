#pragma once
// Live tuning from a keypad (the study's) or the viewer: each key moves one perceptual
// control (door-models.md §2, analysis/model/perceptual_controls.h) by one step, and every change
// is logged. Key map (docs/ab-testing.md):
//
//   +  heavier            heaviness      × step      -  lighter          heaviness      ÷ step
//   U  harder to unlatch  latch_effort   × step      u  easier to unlatch latch_effort  ÷ step
//   C  harder to close    closing_effort × step      c  easier to close  closing_effort ÷ step
//   S  rougher            smoothness     × step      s  smoother         smoothness     ÷ step
//   N  more snap          snap           × step      n  less snap        snap           ÷ step
//   r  reset to the parameter set the tuning started from
//
// step is 1.1 by default. A step that would take a parameter outside its bounds (those of
// the parameter set) or break the model's constraints is refused with a message naming the
// control and the limit; the model stays as it was.
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/session/session_file.h"
#include "analysis/model/door_model.h"
#include "analysis/model/perceptual_controls.h"

namespace doorbench::study {

struct TuningKey {
  char key;
  perceptual::Control control;
  bool increase;            // × step when true, ÷ step otherwise
  std::string_view action;  // "heavier", "easier to unlatch", ...
};

// Every key but reset, in the order of the table above.
std::span<const TuningKey> tuning_keys();
inline constexpr char kResetKey = 'r';
// The key map as text, one key a line (for a help screen).
std::string key_map_text();

struct KeyOptions {
  double step_factor = 1.1;      // one key press multiplies or divides its control by this
  std::string validate() const;  // empty when usable, else one line naming the option
};

struct KeyOutcome {
  std::optional<DoorModel> model;  // the new model; nullopt when refused (or unknown key)
  std::string action;              // "heavier", "reset", ...
  std::string control;             // "heaviness", ... (empty for reset / unknown keys)
  std::string unit;
  double old_value = 0.0, new_value = 0.0;
  std::string message;  // why refused, or what changed ("heaviness 0.95 -> 1.045 kg*m^2")
};

// One key press on `model` (a sensory model). Reset is not handled here (it needs the
// starting model: see KeyTuner). Unknown keys are refused with a message listing the keys.
KeyOutcome apply_key(const DoorModel& model, char key, const KeyOptions& options = {});

struct TuningLogEntry {
  double time_s = 0.0;  // on the session's clock (the caller's)
  char key = 0;
  std::string action, control, unit;
  double old_value = 0.0, new_value = 0.0;
  bool applied = false;
  std::string parameter_set_id;  // the set in force after the press
  std::string message;
};

class TuningLog {
 public:
  void record(TuningLogEntry entry) { entries_.push_back(std::move(entry)); }
  const std::vector<TuningLogEntry>& entries() const { return entries_; }
  // time_s,key,action,control,old,new,unit,applied,parameter_set,message
  std::string to_csv() const;
  // Each entry as an event of kind "tuning" at its time, and the whole log as the text
  // attribute tuning/log_csv.
  void write_to_session(SessionWriter& writer) const;

 private:
  std::vector<TuningLogEntry> entries_;
};

// The tuning of one session: the starting model, the current one, and the log. Parameter
// set ids are `base_id` for the start and `base_id`-1, -2, ... for each applied change
// (a reset goes back to `base_id`).
class KeyTuner {
 public:
  KeyTuner(DoorModel start, std::string base_id, const KeyOptions& options = {});
  // Applies the key at `time_s` and logs it (refusals too).
  const TuningLogEntry& press(char key, double time_s);
  const DoorModel& model() const { return current_; }
  const std::string& parameter_set_id() const { return current_id_; }
  const TuningLog& log() const { return log_; }
  // The log (TuningLog::write_to_session), and the starting and current parameter sets as
  // parameter files (attributes tuning/start_parameters_json, tuning/final_parameters_json)
  // with the current set's id (tuning/final_parameter_set): the feel the tuning ended on.
  void write_to_session(SessionWriter& writer) const;

 private:
  DoorModel start_, current_;
  std::string base_id_, current_id_;
  KeyOptions options_;
  int changes_ = 0;
  TuningLog log_;
};

// Single key presses from a terminal (the keypad is a USB keyboard) without waiting for
// Enter: for the object's lifetime the terminal is in non-canonical mode without echo, and
// its settings are restored afterwards (also when the program ends by an exception). Not
// for the tick: poll() is a system call; call it from the operator's thread and hand the
// resulting parameter set to the loop.
class TerminalKeys {
 public:
  // Throws std::runtime_error when `fd` is not a terminal ("`name` is not a terminal: ...").
  explicit TerminalKeys(int fd, const std::string& name = "stdin");
  ~TerminalKeys();
  TerminalKeys(const TerminalKeys&) = delete;
  TerminalKeys& operator=(const TerminalKeys&) = delete;
  // The next key, waiting at most timeout_s (0: only what is already there); nullopt when
  // none came. Throws std::runtime_error when the terminal is gone (end of input, error).
  std::optional<char> poll(double timeout_s = 0.0);

 private:
  int fd_;
  std::string name_;
  std::vector<unsigned char> saved_;  // the terminal's settings before (a struct termios)
};

}  // namespace doorbench::study
