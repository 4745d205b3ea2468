#pragma once
// A loaded machine on demand, for the tests of what must hold under load (the haptic loop,
// the timing of real-time plays): `count` child processes, each spinning on one CPU at the
// normal priority, started by the constructor and killed (SIGKILL, then reaped) by the
// destructor. A child also dies with the test process (PR_SET_PDEATHSIG), so a test that
// crashes leaves no spinner behind. The default count is twice the hardware threads: more
// runnable processes than cores, as a build running beside the rig brings.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <thread>
#include <vector>

namespace doorbench::testing {

class BusyProcesses {
 public:
  static unsigned twice_the_cores() {
    return 2 * std::max(1u, std::thread::hardware_concurrency());
  }

  explicit BusyProcesses(unsigned count = twice_the_cores()) {
    const pid_t parent = ::getpid();
    for (unsigned i = 0; i < count; ++i) {
      const pid_t pid = ::fork();
      if (pid < 0) {
        end();
        throw std::runtime_error("BusyProcesses: fork failed");
      }
      if (pid == 0) {
        // Only async-signal-safe calls after fork() in a threaded process: prctl, getppid,
        // then a bare loop.
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (::getppid() != parent) ::_exit(0);
        volatile unsigned long spin = 0;
        for (;;) spin = spin + 1;
      }
      pids_.push_back(pid);
    }
  }
  ~BusyProcesses() { end(); }
  BusyProcesses(const BusyProcesses&) = delete;
  BusyProcesses& operator=(const BusyProcesses&) = delete;

  std::size_t count() const { return pids_.size(); }

 private:
  void end() noexcept {
    for (const pid_t pid : pids_) ::kill(pid, SIGKILL);
    for (const pid_t pid : pids_) {
      int status = 0;
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
    }
    pids_.clear();
  }

  std::vector<pid_t> pids_;
};

}  // namespace doorbench::testing
