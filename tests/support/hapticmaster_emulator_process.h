#pragma once
// The HapticMaster protocol emulator (tests/hapticmaster_emulator/hapticmaster_emulator.py,
// docs/hapticmaster.md) as a child process on a free loopback port, for the tests that talk
// to it. `options` are the emulator's command-line options (--drop-after N, --log FILE, ...).
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/modbus_test_server.h"  // ChildProcess

namespace doorbench::testing {

struct HapticMasterEmulator {
  ChildProcess process;
  int port = 0;
  explicit HapticMasterEmulator(const std::vector<std::string>& options = {})
      : process([&] {
          std::vector<std::string> args = {
              "/usr/bin/python3",
              std::string(DOORBENCH_SOURCE_DIR)
                  .append("/tests/hapticmaster_emulator/hapticmaster_emulator.py")};
          args.insert(args.end(), options.begin(), options.end());
          return args;
        }()) {
    const std::string line = process.read_line();
    if (line.rfind("PORT ", 0) != 0) throw std::runtime_error("emulator said: " + line);
    port = std::stoi(line.substr(5));
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port); }
  std::string name() const { return "hapticmaster://" + address(); }
};

}  // namespace doorbench::testing
