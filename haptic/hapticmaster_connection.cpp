#include "haptic/hapticmaster_connection.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

namespace doorbench::haptic::hm {
namespace {

using Clock = std::chrono::steady_clock;

int millis_left(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<long long>(0, left.count()));
}

Clock::time_point after(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace

Connection::Connection(const std::string& host, int port, double timeout_s) {
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
      why = "connect timed out after " + format_device_number(timeout_s) + " s";
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
Connection::~Connection() {
  ::close(fd_);
}

std::vector<std::string> Connection::round_trip(const std::vector<std::string>& commands,
                                                double timeout_s, bool joined) {
  const auto deadline = after(timeout_s);
  const std::string bytes = request(commands, joined);
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
      for (std::string& reply : split_replies(*message)) replies.push_back(std::move(reply));
    }
    if (splitter_.corrupt()) throw std::runtime_error(splitter_.error());
    if (messages == messages_expected) break;
    // The deadline is checked here too: a device trickling bytes must not extend it.
    pollfd p{fd_, POLLIN, 0};
    if (Clock::now() >= deadline || ::poll(&p, 1, millis_left(deadline)) == 0) {
      throw std::runtime_error("no reply within " + format_device_number(timeout_s) + " s");
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

}  // namespace doorbench::haptic::hm
