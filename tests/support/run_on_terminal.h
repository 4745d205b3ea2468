#pragma once
// Runs the doorbench executable with its stdin on a real pseudo-terminal (openpty), as an
// operator's keyboard or keypad would be, for tests of interactive input; or with its stdout
// and stderr on one (forkpty), for tests of what a terminal shows (status lines redrawn in
// place). `typed` is written to
// the terminal after `delay_ms`; the terminal's echo is drained until doorbench exits (so that it
// never blocks on it). stdout and stderr go to files in `dir`.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace doorbench::testing {

inline DoorbenchRun run_doorbench_on_terminal(const std::vector<std::string>& args,
                                              const TempDir& dir, const std::string& typed,
                                              int delay_ms = 0) {
  const std::string out_path = (dir / "stdout.txt").string();
  const std::string err_path = (dir / "stderr.txt").string();
  DoorbenchRun run;
  // Built before the fork: the child only calls what is safe after one (no allocation).
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(DOORBENCH_EXECUTABLE));
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  int master = -1, slave = -1;
  if (::openpty(&master, &slave, nullptr, nullptr, nullptr) != 0) return run;
  const pid_t child = ::fork();
  if (child < 0) return run;
  if (child == 0) {
    ::dup2(slave, STDIN_FILENO);
    ::close(master);
    ::close(slave);
    const int out_fd = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out_fd, STDOUT_FILENO);
    ::dup2(err_fd, STDERR_FILENO);
    ::execv(DOORBENCH_EXECUTABLE, argv.data());
    ::_exit(127);
  }
  ::close(slave);
  std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
  if (::write(master, typed.data(), typed.size()) != static_cast<ssize_t>(typed.size())) {
    run.err = "could not type on the terminal";
  }
  int status = 0;
  for (int waited_ms = 0; waited_ms < 60000; waited_ms += 10) {
    char echo[256];
    pollfd request{master, POLLIN, 0};
    if (::poll(&request, 1, 10) > 0 && (request.revents & POLLIN)) {
      if (::read(master, echo, sizeof echo) <= 0) break;
    }
    if (::waitpid(child, &status, WNOHANG) == child) break;
  }
  if (::waitpid(child, &status, WNOHANG) == 0) ::waitpid(child, &status, 0);
  ::close(master);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream o(out_path), e(err_path);
  std::stringstream os, es;
  os << o.rdbuf();
  es << e.rdbuf();
  run.out = os.str();
  run.err.append(es.str());
  return run;
}

// doorbench ARGS (a shell command line's arguments) with stdout and stderr on a
// pseudo-terminal; returns everything it wrote there, its exit status in `status`.
inline std::string run_doorbench_terminal_output(const std::string& args, int& status) {
  // Built before the fork: the child only calls what is safe after one.
  const std::string command = std::string("'" DOORBENCH_EXECUTABLE "' ") + args;
  int master = -1;
  const pid_t child = ::forkpty(&master, nullptr, nullptr, nullptr);
  if (child < 0) return "";
  if (child == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::string output;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(master, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // EIO once the child closed the terminal
    output.append(buffer, std::size_t(n));
  }
  int wait_status = 0;
  ::waitpid(child, &wait_status, 0);
  ::close(master);
  status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
  return output;
}

}  // namespace doorbench::testing
