#pragma once
// The Modbus test servers as real processes (tests/modbus/transmitter_server.py on Debian's
// /usr/bin/python3 with python3-pymodbus; socat for RTU's pseudo-terminal pair), each
// killed and reaped when its guard goes out of scope, and the server's register formulas.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace doorbench::testing {

// The server's signals (transmitter_server.py), t in CLOCK_MONOTONIC seconds.
inline double server_force_N(double t) {
  return 50.0 + 40.0 * std::sin(2 * std::numbers::pi * 0.5 * t);
}
inline double server_angle_deg(double t) {
  return 5.0 * std::sin(2 * std::numbers::pi * 0.2 * t);
}
inline double server_rate_dps(double t) {
  return 5.0 * 2 * std::numbers::pi * 0.2 * std::cos(2 * std::numbers::pi * 0.2 * t);
}
// Their largest rates of change (per second), to bound a value's change over a latency.
constexpr double kForceMaxSlope_N_per_s = 40.0 * 2 * std::numbers::pi * 0.5;
constexpr double kAngleMaxSlope_deg_per_s = 5.0 * 2 * std::numbers::pi * 0.2;

// A child process, its stdout on a pipe; SIGKILLed and reaped on destruction.
class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& args) {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
    std::vector<std::string> storage = args;
    std::vector<char*> argv;
    for (std::string& arg : storage) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int null_fd = ::open("/dev/null", O_RDWR);
      ::dup2(null_fd, 0);
      ::dup2(fds[1], 1);
      ::dup2(null_fd, 2);  // pymodbus logs client disconnections there
      ::close(fds[0]);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(fds[1]);
    out_fd_ = fds[0];
  }
  ~ChildProcess() { kill(); }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // The child's next stdout line; throws after `timeout_s` or when it ends.
  std::string read_line(double timeout_s = 10.0) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    std::string line;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) throw std::runtime_error("child process: no output line in time");
      pollfd p{out_fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char c = 0;
      if (::read(out_fd_, &c, 1) != 1) throw std::runtime_error("child process ended: " + line);
      if (c == '\n') return line;
      line += c;
    }
  }

  pid_t pid() const { return pid_; }
  // Sends `signal_number` to the child.
  void send_signal(int signal_number) {
    if (pid_ > 0) ::kill(pid_, signal_number);
  }
  // Waits up to `timeout_s` for the child to end; its exit status (128 + signal when a signal
  // ended it), or -1 if it is still running.
  int wait_exit(double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (pid_ > 0) {
      int status = 0;
      const pid_t done = ::waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (std::chrono::steady_clock::now() > deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1;
  }

  void kill() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
    if (out_fd_ >= 0) {
      ::close(out_fd_);
      out_fd_ = -1;
    }
  }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
};

inline std::string transmitter_server_script() {
  return std::string(DOORBENCH_SOURCE_DIR).append("/tests/modbus/transmitter_server.py");
}

// A TCP server on loopback; `port` is the one it bound.
struct TcpTransmitterServer {
  ChildProcess process;
  int port = 0;
  explicit TcpTransmitterServer(std::vector<std::string> options = {})
      : process([&] {
          std::vector<std::string> args = {"/usr/bin/python3", transmitter_server_script()};
          args.insert(args.end(), options.begin(), options.end());
          return args;
        }()) {
    const std::string line = process.read_line();
    if (line.rfind("PORT ", 0) != 0) throw std::runtime_error("server said: " + line);
    port = std::stoi(line.substr(5));
  }
};

// A socat pseudo-terminal pair: `server_end` and `client_end` are its two devices.
struct PtyPair {
  std::filesystem::path server_end;
  std::filesystem::path client_end;
  ChildProcess process;
  explicit PtyPair(const std::filesystem::path& dir)
      : server_end(dir / "server_tty"),
        client_end(dir / "client_tty"),
        process({"/usr/bin/socat", "pty,raw,echo=0,link=" + server_end.string(),
                 "pty,raw,echo=0,link=" + client_end.string()}) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!std::filesystem::exists(server_end) || !std::filesystem::exists(client_end)) {
      if (std::chrono::steady_clock::now() > deadline) throw std::runtime_error("socat: no ptys");
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
};

// An RTU server on `pty`'s server end.
struct RtuTransmitterServer {
  ChildProcess process;
  RtuTransmitterServer(const PtyPair& pty, std::vector<std::string> options = {})
      : process([&] {
          std::vector<std::string> args = {"/usr/bin/python3", transmitter_server_script(),
                                           "--transport",      "rtu",
                                           "--device",         pty.server_end.string()};
          args.insert(args.end(), options.begin(), options.end());
          return args;
        }()) {
    const std::string line = process.read_line();
    if (line != "READY") throw std::runtime_error("server said: " + line);
  }
};

}  // namespace doorbench::testing
