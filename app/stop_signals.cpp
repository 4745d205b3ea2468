// SIGINT and SIGTERM for the verbs that stop cleanly (app/stop_signals.h).
#include "app/stop_signals.h"

#include <signal.h>

#include <atomic>

namespace doorbench::app {
namespace {

std::atomic<int> g_received{0};
std::atomic<bool> g_installed{false};
static_assert(std::atomic<int>::is_always_lock_free, "the handler's store must be lock-free");
struct sigaction g_old_int {};
struct sigaction g_old_term {};

// Only a lock-free atomic store and sigaction's async-signal-safe sibling signal().
extern "C" void on_verb_stop_signal(int signal_number) {
  int none = 0;
  g_received.compare_exchange_strong(none, signal_number);
  ::signal(signal_number, SIG_DFL);  // a second signal ends the process at once
}

}  // namespace

StopSignals::StopSignals() {
  if (g_installed.exchange(true)) throw std::logic_error("StopSignals: already installed");
  g_received.store(0);
  struct sigaction action {};
  action.sa_handler = on_verb_stop_signal;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &g_old_int);
  ::sigaction(SIGTERM, &action, &g_old_term);
}

StopSignals::~StopSignals() {
  ::sigaction(SIGINT, &g_old_int, nullptr);
  ::sigaction(SIGTERM, &g_old_term, nullptr);
  g_installed.store(false);
}

int StopSignals::received() const {
  return g_received.load();
}

std::string signal_name(int signal_number) {
  if (signal_number == SIGINT) return "SIGINT";
  if (signal_number == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal_number);
}

Interrupted nothing_finished(int signal_number, const std::string& verb, const std::string& what,
                             const std::string& where, const std::string& out_dir) {
  return Interrupted(signal_number, verb + ": " + signal_name(signal_number) + " stopped " + what +
                                        " during " + where +
                                        ": nothing was finished; nothing "
                                        "written to " +
                                        out_dir + "/");
}

}  // namespace doorbench::app
