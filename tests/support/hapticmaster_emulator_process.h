#pragma once
// The HapticMaster protocol emulator (tests/hapticmaster_emulator/hapticmaster_emulator.py,
// docs/hapticmaster.md) as a child process on a free loopback port, for the tests that talk
// to it. `options` are the emulator's command-line options (--drop-after N, --log FILE, ...).
//
// The emulator stands for the HapticMaster's own controller, a computer of its own that the
// host's load does not reach: where the test process may (root, or an rtprio limit), it runs
// under SCHED_FIFO at priority 70 (chrt), below the host's tick (80) and I/O thread (79), so
// that busy processes started by a load test load the host, not the device. Where it may not,
// it runs at the normal priority.
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "fixtures/modbus_test_server.h"  // ChildProcess

namespace doorbench::testing {

struct HapticMasterEmulator {
  std::unique_ptr<ChildProcess> process;
  int port = 0;
  bool realtime = false;  // it runs under SCHED_FIFO
  explicit HapticMasterEmulator(const std::vector<std::string>& options = {}) {
    std::string line = start(options, true);
    realtime = line.rfind("PORT ", 0) == 0;
    if (!realtime) line = start(options, false);  // chrt was refused: the normal priority
    if (line.rfind("PORT ", 0) != 0) throw std::runtime_error("emulator said: " + line);
    port = std::stoi(line.substr(5));
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port); }
  std::string name() const { return "hapticmaster://" + address(); }

 private:
  static std::vector<std::string> arguments(const std::vector<std::string>& options, bool fifo) {
    std::vector<std::string> args;
    if (fifo) args = {"/usr/bin/chrt", "-f", "70"};
    args.push_back("/usr/bin/python3");
    args.push_back(std::string(DOORBENCH_SOURCE_DIR)
                       .append("/tests/hapticmaster_emulator/hapticmaster_emulator.py"));
    args.insert(args.end(), options.begin(), options.end());
    return args;
  }
  // Starts the emulator (under chrt when `fifo`); its first line, or why there is none.
  std::string start(const std::vector<std::string>& options, bool fifo) {
    process = std::make_unique<ChildProcess>(arguments(options, fifo));
    try {
      return process->read_line();
    } catch (const std::runtime_error& ended) {
      return ended.what();
    }
  }
};

}  // namespace doorbench::testing
