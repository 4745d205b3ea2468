#include "haptic/hapticmaster_device.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "haptic/hapticmaster_protocol.h"

namespace doorbench::haptic {
namespace {

using Clock = std::chrono::steady_clock;

double monotonic_s() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

int millis_left(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<long long>(0, left.count()));
}

Clock::time_point after(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// The HapticMaster's figures: where each comes from is in docs/hapticmaster.md (limits).
DeviceLimits hapticmaster_limits() {
  DeviceLimits limits;
  limits.kinematics = Kinematics::kCartesian3;
  limits.max_force = 250.0;         // N: assumed (recalled datasheet figure, not verified here)
  limits.max_velocity = 1.0;        // m/s: assumed
  limits.max_force_rate = 20000.0;  // N/s: assumed (the interface's default)
  // A box inside the workspace a public example describes (radius 0.28..0.64 m about the
  // base axis, 0.45 m behind the origin; +-0.5 rad; z +-0.2 m), x taken as radial: derived.
  limits.workspace_min = Vec3(-0.14, -0.16, -0.2);
  limits.workspace_max = Vec3(0.16, 0.16, 0.2);
  limits.min_inertia = 2.0;    // kg: the smallest value public examples set; assumed
  limits.max_inertia = 100.0;  // kg: assumed
  return limits;
}

// "" if `replies` answer `commands` without error, else what went wrong: the first error
// reply (named by its command) or a wrong count.
std::string check_replies(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies) {
  for (std::size_t i = 0; i < replies.size(); ++i) {
    const hm::Reply reply = hm::parse_reply(replies[i]);
    if (reply.kind == hm::Reply::Kind::kError) {
      const std::string& command = i < commands.size() ? commands[i] : commands.back();
      return "'" + command + "' failed: " + reply.text;
    }
  }
  if (replies.size() != commands.size()) {
    return std::to_string(commands.size()) + " command(s) '" + hm::join_commands(commands) +
           "' answered with " + std::to_string(replies.size()) + " repl" +
           (replies.size() == 1 ? "y" : "ies");
  }
  return "";
}

// The readings at the end of a round trip: checks the replies, then takes the last three
// (measpos, modelvel, measforce) into `sample`. Returns "" or what went wrong.
std::string take_readings(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies, DeviceSample& sample) {
  if (std::string problem = check_replies(commands, replies); !problem.empty()) return problem;
  Vec3* fields[3] = {&sample.position, &sample.velocity, &sample.measured_force};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t i = commands.size() - 3 + k;
    const hm::Reply reply = hm::parse_reply(replies[i]);
    if (reply.kind != hm::Reply::Kind::kVector) {
      return "'" + commands[i] + "' answered '" + reply.text + "', not [x,y,z]";
    }
    *fields[k] = reply.vector;
  }
  return "";
}

const std::vector<std::string> kReadings = {"get measpos", "get modelvel", "get measforce"};

}  // namespace

// The socket, owned by whichever thread currently talks to the device (start/stop or the
// I/O thread, never both). Errors are std::runtime_error with the reason only.
class HapticMasterDevice::Connection {
 public:
  Connection(const std::string& host, int port, double timeout_s) {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    const int gai = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
    if (gai != 0) {
      throw std::runtime_error(std::string("cannot resolve host: ").append(::gai_strerror(gai)));
    }
    std::string why = "no address";
    for (addrinfo* a = found; a != nullptr && fd_ < 0; a = a->ai_next) {
      const int fd =
          ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
      if (fd < 0) {
        why = std::strerror(errno);
        continue;
      }
      if (::connect(fd, a->ai_addr, a->ai_addrlen) != 0 && errno != EINPROGRESS) {
        why = std::strerror(errno);
        ::close(fd);
        continue;
      }
      pollfd p{fd, POLLOUT, 0};
      const int ready = ::poll(&p, 1, static_cast<int>(timeout_s * 1000));
      int error = 0;
      socklen_t length = sizeof error;
      if (ready <= 0) {
        why = "connect timed out after " + hm::format_number(timeout_s) + " s";
      } else if (::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) != 0 || error != 0) {
        why = std::strerror(error != 0 ? error : errno);
      } else {
        fd_ = fd;
        break;
      }
      ::close(fd);
    }
    ::freeaddrinfo(found);
    if (fd_ < 0) throw std::runtime_error("cannot connect: " + why);
    const int one = 1;  // small messages, one round trip each: no Nagle delay
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  }
  ~Connection() { ::close(fd_); }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Sends `commands` (as one joined message or one message each) and returns the replies
  // in order. Normally one per command; fewer if the device skipped some (the caller looks
  // for an error reply first, then at the count).
  std::vector<std::string> round_trip(const std::vector<std::string>& commands, double timeout_s,
                                      bool joined) {
    const auto deadline = after(timeout_s);
    const std::string bytes = hm::request(commands, joined);
    std::size_t sent = 0;
    while (sent < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
      if (n > 0) {
        sent += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        throw std::runtime_error(std::string("send failed: ").append(std::strerror(errno)));
      }
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, millis_left(deadline)) == 0) throw std::runtime_error("send timed out");
    }
    const std::size_t messages_expected = joined ? 1 : commands.size();
    std::size_t messages = 0;
    std::vector<std::string> replies;
    replies.reserve(commands.size());
    char buffer[4096];
    for (;;) {
      while (messages < messages_expected) {
        auto message = splitter_.next();
        if (!message) break;
        ++messages;
        for (std::string& reply : hm::split_replies(*message)) replies.push_back(std::move(reply));
      }
      if (splitter_.corrupt()) throw std::runtime_error(splitter_.error());
      if (messages == messages_expected) break;
      // The deadline is checked here too: a device trickling bytes must not extend it.
      pollfd p{fd_, POLLIN, 0};
      if (Clock::now() >= deadline || ::poll(&p, 1, millis_left(deadline)) == 0) {
        throw std::runtime_error("no reply within " + hm::format_number(timeout_s) + " s");
      }
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n == 0) throw std::runtime_error("connection closed by the device");
      if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
        throw std::runtime_error(std::string("receive failed: ").append(std::strerror(errno)));
      }
      splitter_.feed(std::string_view(buffer, static_cast<std::size_t>(n)));
    }
    return replies;
  }

 private:
  int fd_ = -1;
  hm::ReplySplitter splitter_;
};

std::string HapticMasterOptions::validate() const {
  if (!(connect_timeout_s > 0) || !std::isfinite(connect_timeout_s)) {
    return "connect_timeout_s must be > 0";
  }
  if (!(reply_timeout_s > 0) || !std::isfinite(reply_timeout_s)) {
    return "reply_timeout_s must be > 0";
  }
  if (!(io_rate_hz > 0) || !(io_rate_hz <= 10000)) return "io_rate_hz must be in (0, 10000]";
  if (bias_object.empty() || !std::all_of(bias_object.begin(), bias_object.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
      })) {
    return "bias_object must be a non-empty name of letters, digits and '_'";
  }
  return "";
}

HapticMasterDevice::HapticMasterDevice(const std::string& address, HapticMasterOptions options)
    : options_(std::move(options)) {
  try {
    const hm::Address parsed = hm::parse_address(address);
    host_ = parsed.host;
    port_ = parsed.port;
  } catch (const std::invalid_argument& e) {
    throw DeviceError(std::string("hapticmaster://").append(address).append(": ").append(e.what()));
  }
  if (const std::string problem = options_.validate(); !problem.empty()) {
    throw DeviceError(name() + ": option " + problem);
  }
}

HapticMasterDevice::~HapticMasterDevice() {
  stop();
}

std::string HapticMasterDevice::name() const {
  return "hapticmaster://" + host_ + ":" + std::to_string(port_);
}

DeviceLimits HapticMasterDevice::limits() const {
  return hapticmaster_limits();
}

std::string HapticMasterDevice::expect_ok(const std::string& command) {
  std::vector<std::string> replies;
  try {
    replies = connection_->round_trip({command}, options_.reply_timeout_s, true);
  } catch (const std::exception& e) {
    throw DeviceError(name() + ": '" + command + "': " + e.what());
  }
  if (const std::string problem = check_replies({command}, replies); !problem.empty()) {
    throw DeviceError(name() + ": " + problem);
  }
  return replies.front();
}

void HapticMasterDevice::start(double inertia) {
  if (io_thread_.joinable() || connection_) throw DeviceError(name() + ": already started");
  const DeviceLimits limits = hapticmaster_limits();
  if (!(inertia >= limits.min_inertia && inertia <= limits.max_inertia)) {
    throw DeviceError(name() + ": inertia " +
                      hm::format_number(std::isfinite(inertia) ? inertia : 0) + " kg is outside " +
                      hm::format_number(limits.min_inertia) + ".." +
                      hm::format_number(limits.max_inertia) + " kg");
  }
  try {
    connection_ = std::make_unique<Connection>(host_, port_, options_.connect_timeout_s);
  } catch (const std::exception& e) {
    throw DeviceError(name() + ": " + e.what());
  }
  {
    std::lock_guard<std::mutex> lock(error_mutex_);
    last_error_.clear();
  }
  bool created = false;
  DeviceSample first;
  try {
    // Does it answer at all, and with a state name, quoted or not? (A wrong server fails.)
    const hm::Reply state = hm::parse_reply(expect_ok("get state"));
    const std::string word = state.kind == hm::Reply::Kind::kString ? state.string : state.text;
    if ((state.kind != hm::Reply::Kind::kString && state.kind != hm::Reply::Kind::kMessage) ||
        word.empty() || !std::all_of(word.begin(), word.end(), [](char c) {
          return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
        })) {
      throw DeviceError(name() + ": 'get state' answered '" + state.text +
                        "', not a state name: is this a HapticMaster?");
    }
    const std::string bias = options_.bias_object;
    expect_ok("set inertia " + hm::format_number(inertia));
    // A bias object left by a session that ended without stop() would make create fail;
    // removing one that is not there is an error reply, which does not matter here.
    try {
      connection_->round_trip({"remove " + bias}, options_.reply_timeout_s, true);
    } catch (const std::exception& e) {
      throw DeviceError(name() + ": 'remove " + bias + "': " + e.what());
    }
    expect_ok("create biasforce " + bias);
    created = true;
    expect_ok("set " + bias + " force " + hm::format_vector(Vec3::Zero()));
    expect_ok("set " + bias + " enable");
    expect_ok("set state force");
    // The first reading, so the tick's first read() has a real position (sequence 1).
    std::vector<std::string> replies;
    try {
      replies =
          connection_->round_trip(kReadings, options_.reply_timeout_s, options_.join_commands);
    } catch (const std::exception& e) {
      throw DeviceError(name() + ": first reading: " + e.what());
    }
    first.time_s = monotonic_s();
    if (const std::string problem = take_readings(kReadings, replies, first); !problem.empty()) {
      throw DeviceError(name() + ": " + problem);
    }
    first.sequence = 1;
    first.link_ok = true;
  } catch (...) {
    if (created) {
      link_ok_.store(true);
      send_shutdown();  // best effort: leave the device as stop() would
    }
    link_ok_.store(false);
    connection_.reset();
    throw;
  }

  staged_ = Command{Vec3::Zero(), inertia};
  commands_.back() = staged_;
  commands_.publish();
  samples_.back() = first;
  samples_.publish();
  last_read_ = first;
  round_trips_.store(0);
  stop_requested_.store(false);
  link_ok_.store(true);
  io_thread_ = std::thread([this, inertia, first] { io_loop(inertia, first); });
}

void HapticMasterDevice::fail(const std::string& reason) {
  link_ok_.store(false);
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (last_error_.empty()) last_error_ = name() + ": " + reason;
}

void HapticMasterDevice::io_loop(double sent_inertia, DeviceSample sample) {
  const DeviceLimits limits = hapticmaster_limits();
  const std::string set_force = "set " + options_.bias_object + " force ";
  std::vector<std::string> commands;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / options_.io_rate_hz));
  auto next = Clock::now();
  while (!stop_requested_.load(std::memory_order_acquire)) {
    commands_.update();
    const Command command = commands_.front();
    Vec3 force = command.force;
    if (!force.allFinite()) force = Vec3::Zero();
    const double norm = force.norm();
    if (norm > limits.max_force) force *= limits.max_force / norm;
    commands.clear();
    commands.push_back(set_force + hm::format_vector(force));
    const bool new_inertia = command.inertia != sent_inertia;
    if (new_inertia) commands.push_back("set inertia " + hm::format_number(command.inertia));
    commands.insert(commands.end(), kReadings.begin(), kReadings.end());
    std::string problem;
    try {
      const std::vector<std::string> replies =
          connection_->round_trip(commands, options_.reply_timeout_s, options_.join_commands);
      const double now_s = monotonic_s();
      DeviceSample reading = sample;
      problem = take_readings(commands, replies, reading);
      if (problem.empty()) {
        if (new_inertia) sent_inertia = command.inertia;
        sample = reading;
        sample.time_s = now_s;
        ++sample.sequence;
        sample.link_ok = true;
        samples_.back() = sample;
        samples_.publish();
        round_trips_.fetch_add(1, std::memory_order_relaxed);
      }
    } catch (const std::exception& e) {
      problem = e.what();
    }
    if (!problem.empty()) {
      fail(problem);
      sample.link_ok = false;
      samples_.back() = sample;
      samples_.publish();
      return;  // the render loop ramps down and stops; no reconnecting mid-session
    }
    next += period;
    const auto now = Clock::now();
    if (next < now) {
      next = now;  // the link is slower than the rate: go on at once, don't burst later
    } else {
      std::this_thread::sleep_until(next);
    }
  }
}

void HapticMasterDevice::stop() noexcept {
  stop_requested_.store(true, std::memory_order_release);
  if (io_thread_.joinable()) io_thread_.join();
  if (connection_ && link_ok_.load()) send_shutdown();
  connection_.reset();
  link_ok_.store(false);
}

void HapticMasterDevice::send_shutdown() noexcept {
  // Each on its own so one failing does not skip the others; a lost link skips the rest.
  for (const std::string& command :
       {"set " + options_.bias_object + " force " + hm::format_vector(Vec3::Zero()),
        std::string("set state stop"), "remove " + options_.bias_object}) {
    try {
      const auto replies = connection_->round_trip({command}, options_.reply_timeout_s, true);
      if (const std::string problem = check_replies({command}, replies); !problem.empty()) {
        fail(problem);
      }
    } catch (const std::exception& e) {
      fail("'" + command + "': " + e.what());
      break;
    }
  }
}

DeviceSample HapticMasterDevice::read() noexcept {
  if (samples_.update()) last_read_ = samples_.front();
  return last_read_;
}

void HapticMasterDevice::command_force(const Vec3& force) noexcept {
  staged_.force = force;
  commands_.back() = staged_;
  commands_.publish();
}

void HapticMasterDevice::command_inertia(double inertia) noexcept {
  const DeviceLimits limits = hapticmaster_limits();
  if (!std::isfinite(inertia)) return;
  staged_.inertia = std::clamp(inertia, limits.min_inertia, limits.max_inertia);
  commands_.back() = staged_;
  commands_.publish();
}

std::string HapticMasterDevice::last_error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

}  // namespace doorbench::haptic
