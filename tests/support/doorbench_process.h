#pragma once
// doorbench as a child process for the tests of long verbs stopped by a signal: its stderr on
// a pipe the test reads (wait_for a stage line), stdout in a file, the exit status decoded.
// The destructor kills and reaps a child still running.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

namespace doorbench::testing {

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

}  // namespace doorbench::testing
