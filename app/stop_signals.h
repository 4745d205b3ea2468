#pragma once
// SIGINT and SIGTERM for the long verbs that stop cleanly (`fit`, `loop`, `spec`, `campaign
// analyze`, `play`; docs/residual-loop.md, "Interrupting the loop"): while a StopSignals
// lives, the first such signal only records its number (a lock-free atomic store,
// async-signal-safe) and restores the default action, so a second one ends doorbench at once;
// the verb asks received() (directly, or as the StopHook its computation asks,
// core/stop_request.h), writes what it has finished, marked interrupted, and throws
// Interrupted, which main()
// turns into exit status 128 + the signal's number (130 for SIGINT, 143 for SIGTERM), as a
// shell reports a process the signal ended.
//
// Thread safety: one StopSignals at a time per process (the handlers are process-wide);
// received() may be called from any thread.
#include <csignal>
#include <stdexcept>
#include <string>

namespace doorbench::app {

class StopSignals {
 public:
  StopSignals();   // installs the handlers; throws std::logic_error if one is already installed
  ~StopSignals();  // restores the handlers it replaced
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  int received() const;  // the first signal's number, 0 when none arrived
};

// "SIGINT", "SIGTERM", else "signal N".
std::string signal_name(int signal_number);

// Thrown by a verb that stopped on a signal after writing its marked result; main() prints
// the message and exits with exit_status().
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal_number, const std::string& message)
      : std::runtime_error(message), signal_number_(signal_number) {}
  int signal_number() const { return signal_number_; }
  int exit_status() const { return 128 + signal_number_; }

 private:
  int signal_number_;
};

// The Interrupted for a verb stopped before anything was finished: "VERB: SIGINT stopped WHAT
// during WHERE: nothing was finished; nothing written to OUT/".
Interrupted nothing_finished(int signal_number, const std::string& verb, const std::string& what,
                             const std::string& where, const std::string& out_dir);

}  // namespace doorbench::app
