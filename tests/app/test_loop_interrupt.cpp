// `doorbench loop` stopped by SIGINT or SIGTERM after its first step (issue 33, "Long verbs
// stop cleanly"): result.json and report.md are written with the finished steps, marked
// interrupted, and the exit status is 128 + the signal's number (app/stop_signals.h).
//
// The signal is sent when the loop's stderr says its first step was added (the stage line
// `step 1: added ...`), not after a fixed sleep: the loop on this recording has a second
// step and the structure check left (seconds), so the signal always lands before its end.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/files.h"
#include "tests/support/loop_recording.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/temp_dir.h"

namespace {

using doorbench::testing::read_file;
using doorbench::testing::TempDir;

// doorbench as a child process, its stderr on a pipe the test reads, stdout in a file.
class DoorbenchProcess {
 public:
  DoorbenchProcess(const std::vector<std::string>& args, const std::string& stdout_path) {
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    std::vector<std::string> storage = {DOORBENCH_EXECUTABLE};
    storage.insert(storage.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& arg : storage) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      const int null_fd = ::open("/dev/null", O_RDONLY);
      const int out_fd = ::open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(null_fd, 0);
      ::dup2(out_fd, 1);
      ::dup2(fds[1], 2);
      ::close(fds[0]);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(fds[1]);
    err_fd_ = fds[0];
  }
  ~DoorbenchProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (err_fd_ >= 0) ::close(err_fd_);
  }
  DoorbenchProcess(const DoorbenchProcess&) = delete;
  DoorbenchProcess& operator=(const DoorbenchProcess&) = delete;

  // Reads stderr until it holds `text` (true) or ends, or `timeout_s` passes (false).
  bool wait_for(const std::string& text, double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (err_.find(text) == std::string::npos) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0 || !read_some(static_cast<int>(left.count()))) return false;
    }
    return true;
  }
  void send_signal(int signal_number) { ::kill(pid_, signal_number); }
  // Drains stderr to its end and reaps the child: its exit status, or -1 if a signal ended it
  // or it did not end within `timeout_s`.
  int wait_exit(double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline && read_some(100)) {
    }
    while (pid_ > 0 && std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }
  const std::string& err() const { return err_; }

 private:
  // Appends what stderr has within `timeout_ms`; false at its end.
  bool read_some(int timeout_ms) {
    pollfd p{err_fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return true;
    char buffer[4096];
    const ssize_t n = ::read(err_fd_, buffer, sizeof buffer);
    if (n <= 0) return false;
    err_.append(buffer, static_cast<std::size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  int err_fd_ = -1;
  std::string err_;
};

}  // namespace

TEST_CASE("loop: SIGINT or SIGTERM after the first step leaves a readable result marked "
          "interrupted",
          "[cli][loop][signal]") {
  const TempDir dir("loop_interrupt");
  // The reference door with two effects its start model lacks: the loop adds the gravity
  // imbalance at step 1, the viscous damping at step 2, then runs the structure check.
  const std::string csv = doorbench::testing::simulate_loop_recording(dir);
  for (const int signal_number : {SIGINT, SIGTERM}) {
    const std::string name = signal_number == SIGINT ? "SIGINT" : "SIGTERM";
    DYNAMIC_SECTION(name) {
      const auto out = dir / ("out-" + name);
      DoorbenchProcess loop({"loop", csv, "--out", out.string()},
                            (dir / ("stdout-" + name + ".txt")).string());
      REQUIRE(loop.wait_for("\nstep 1: added gravity_imbalance", 600));
      loop.send_signal(signal_number);
      const int status = loop.wait_exit(600);
      INFO(loop.err());
      CHECK(status == 128 + signal_number);

      const nlohmann::json result = nlohmann::json::parse(read_file(out / "result.json"));
      CHECK(result.at("interrupted") == true);
      const std::string stop_reason = result.at("stop_reason");
      CHECK(stop_reason.rfind("interrupted ", 0) == 0);
      REQUIRE(result.at("steps").size() >= 1);
      CHECK(result.at("steps").at(0).at("effect") == "gravity_imbalance");
      CHECK(result.at("structure_check").at("ran") == false);
      CHECK(result.at("structure_check").at("reason") == "not run: the loop was interrupted");

      const std::size_t steps = result.at("steps").size();
      const std::string kept = steps == 1 ? "the 1 step finished before it is kept"
                                          : "the 2 steps finished before it are kept";
      const std::string line = name + " stopped the loop: " + stop_reason + "; " + kept +
                               ", the structure check was not run";
      // report.md: its title, then the line.
      const std::string report = read_file(out / "report.md");
      CHECK_THAT(report, Catch::StartsWith("# Residual loop: the sensory model on "));
      const std::size_t title_end = report.find("\n\n");
      REQUIRE(title_end != std::string::npos);
      CHECK(report.substr(title_end + 2, line.size() + 3) == line + ".\n\n");
      CHECK_THAT(loop.err(), Catch::EndsWith("\ndoorbench: loop: " + line + "; the results in " +
                                             out.string() + "/ are marked interrupted\n"));
      CHECK_THAT(read_file(dir / ("stdout-" + name + ".txt")),
                 Catch::StartsWith("Residual loop (interrupted: the steps finished before it): " +
                                   std::to_string(steps) + " effect"));
      // The fitted files are the last accepted model's, written beside it.
      CHECK(std::filesystem::exists(out / "fitted-params.json"));
      CHECK(std::filesystem::exists(out / "fitted-effects.json"));
    }
  }
}
