#pragma once
// One TCP connection to a HapticMaster (docs/hapticmaster.md): a non-blocking connect with a
// timeout, TCP_NODELAY, and round trips of framed requests (hapticmaster_protocol.h) under a
// deadline that a device trickling bytes cannot extend.
//
// Errors are std::runtime_error with the reason only ("cannot connect: ...", "connection
// closed by the device", "no reply within 0.5 s", a corrupt stream's reason); the driver puts
// its name before them. Thread safety: owned by one thread at a time (the driver's set-up
// thread or its I/O thread, never both).
#include <string>
#include <vector>

#include "haptic/hapticmaster_protocol.h"

namespace doorbench::haptic::hm {

class Connection {
 public:
  // Resolves `host` and connects within `timeout_s`; throws std::runtime_error.
  Connection(const std::string& host, int port, double timeout_s);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Sends `commands` (as one joined message or one message each) and returns the replies in
  // order: normally one per command, fewer if the device skipped some (the caller looks for
  // an error reply first, then at the count). Throws std::runtime_error when the connection
  // closes, the stream is corrupt or no whole reply came within `timeout_s`.
  std::vector<std::string> round_trip(const std::vector<std::string>& commands, double timeout_s,
                                      bool joined);

 private:
  int fd_ = -1;
  ReplySplitter splitter_;
};

}  // namespace doorbench::haptic::hm
