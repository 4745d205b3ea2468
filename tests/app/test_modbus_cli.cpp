// doorbench devices --rig against a real Modbus server process on loopback
// (tests/modbus/transmitter_server.py), through the doorbench executable.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "fixtures/modbus_test_server.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

using Catch::Matchers::Contains;
using doorbench::testing::TcpTransmitterServer;
using doorbench::testing::TempDir;

namespace {

using Run = doorbench::testing::DoorbenchRun;

// rigs/modbus-bench.toml's channels, pointed at the test server: force (unit 1, float32
// ABCD at 0), angle (unit 2, int16 at 8) and one register past the server's map.
std::string rig_text(int port) {
  return "[bench]\nname = \"probe\"\n[daq]\nbackend = \"none\"\n"
         "[[modbus.devices]]\nname = \"gateway\"\ntransport = \"tcp\"\nhost = \"127.0.0.1\"\n"
         "port = " +
         std::to_string(port) +
         "\n"
         "[[channels]]\nname = \"force\"\nsensor = \"load_cell\"\nserial = \"a\"\nbackend = "
         "\"modbus\"\nunit = \"N\"\n[channels.modbus]\ndevice = \"gateway\"\nunit_id = 1\n"
         "register = \"input\"\naddress = 0\ntype = \"float32\"\nbyte_order = \"big\"\n"
         "word_order = \"big\"\nrange = [-700, 700]\npoll_rate_hz = 100\n"
         "[[channels]]\nname = \"angle\"\nsensor = \"inclinometer\"\nserial = \"b\"\nbackend = "
         "\"modbus\"\nunit = \"rad\"\n[channels.modbus]\ndevice = \"gateway\"\nunit_id = 2\n"
         "register = \"input\"\naddress = 8\ntype = \"int16\"\nbyte_order = \"big\"\n"
         "scale = 1.7453292519943296e-4\nrange = [-0.2, 0.2]\npoll_rate_hz = 100\n"
         "[[channels]]\nname = \"beyond\"\nsensor = \"gyroscope\"\nserial = \"c\"\nbackend = "
         "\"modbus\"\nunit = \"rad/s\"\n[channels.modbus]\ndevice = \"gateway\"\nunit_id = 3\n"
         "register = \"holding\"\naddress = 100\ntype = \"int16\"\nbyte_order = \"big\"\n"
         "range = [-2, 2]\npoll_rate_hz = 100\n";
}

}  // namespace

TEST_CASE("doorbench devices --rig probes the rig's Modbus sensors", "[modbus][cli]") {
  TempDir dir("modbus_cli");
  std::filesystem::create_directories(dir / "dev");
  int port = 0;
  {
    TcpTransmitterServer server;
    port = server.port;
    dir.write("rig.toml", rig_text(port));
    const Run run =
        doorbench::testing::run_doorbench_shell("devices --dev-dir '" + (dir / "dev").string() +
                                                    "' --rig '" + (dir / "rig.toml").string() + "'",
                                                dir);
    INFO(run.out << run.err);
    CHECK(run.status == 0);
    CHECK_THAT(run.out, Contains("modbus device gateway (tcp 127.0.0.1:" + std::to_string(port) +
                                 "): connected\n"));
    CHECK_THAT(run.out, Contains("  force (unit 1, input register 0, float32): "));
    CHECK_THAT(run.out, Contains("  angle (unit 2, input register 8, int16): "));
    CHECK_THAT(run.out, Contains(" rad (register value "));
    CHECK_THAT(run.out, Contains("  beyond (unit 3, holding register 100, int16): exception reply: "
                                 "Illegal data address\n"));
    // The force is the server's 50 ± 40 N, with a latency.
    const std::size_t at = run.out.find("float32): ");
    REQUIRE(at != std::string::npos);
    const double force = std::stod(run.out.substr(at + 10));
    CHECK(force >= 9.9);
    CHECK(force <= 90.1);
    CHECK_THAT(run.out, Contains(" N (register value "));
    CHECK_THAT(run.out, Contains(" ms\n"));
  }
  // The server is gone: the probe says so and goes on.
  const Run refused =
      doorbench::testing::run_doorbench_shell("devices --dev-dir '" + (dir / "dev").string() +
                                                  "' --rig '" + (dir / "rig.toml").string() + "'",
                                              dir);
  CHECK(refused.status == 0);
  CHECK_THAT(refused.out, Contains("modbus device gateway (tcp 127.0.0.1:" + std::to_string(port) +
                                   "): cannot connect: connection refused\n"));
  // A Modbus-only rig records for a set time or through its triggers.
  const Run record = doorbench::testing::run_doorbench_shell(
      "record --rig '" + (dir / "rig.toml").string() + "' --out '" + (dir / "s.h5").string() + "'",
      dir);
  CHECK(record.status == 2);
  CHECK_THAT(record.err, Contains("a rig of polled sensors records for a set time: give "
                                  "--duration-s (or a [recording] table with its triggers)"));
}
