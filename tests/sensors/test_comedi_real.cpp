// Debian's real libcomedi (linked): what it can do without a card. A missing device gives
// a clear message naming it, `doorbench devices` says there is none, and the conversion
// functions, which need no device, agree with the emulator's (so the emulator's
// conversions are checked against the real library, not against themselves).
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/comedi_api.h"
#include "sensors/comedi_backend.h"
#include "sensors/comedi_devices.h"

using Catch::Matchers::Contains;
using doorbench::sensors::ComediApi;
using doorbench::testing::TempDir;

namespace {

const ComediApi& real() {
  return doorbench::sensors::linked_comedilib();
}
const ComediApi& emulated() {
  return doorbench::sensors::load_comedi_library(DOORBENCH_COMEDI_EMULATOR);
}

std::string reference_rig_with_device(const std::string& device) {
  std::ifstream in(std::string(DOORBENCH_SOURCE_DIR) + "/rigs/reference-bench.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string rig = text.str();
  const std::string from = "device = \"/dev/comedi0\"";
  const auto at = rig.find(from);
  REQUIRE(at != std::string::npos);
  return rig.replace(at, from.size(), "device = \"" + device + "\"");
}

}  // namespace

TEST_CASE("real libcomedi: a missing device file gives a message naming it", "[comedi][real]") {
  CHECK(real().name == "libcomedi (linked)");
  TempDir dir("comedi_real");
  const std::string device = (dir / "comedi0").string();
  const auto rig = doorbench::parse_rig(reference_rig_with_device(device), "reference-bench.toml",
                                        DOORBENCH_SOURCE_DIR "/rigs");
  REQUIRE_THROWS_WITH(
      doorbench::sensors::ComediBackend(rig, real()),
      device +
          ": cannot open the comedi device: No such file or directory (no such device file: "
          "is a card installed, its comedi driver loaded and the device configured? A USB "
          "cDAQ-9172 has no comedi driver)");
  // The real library's own view of the same failure.
  CHECK(real().open(device.c_str()) == nullptr);
  CHECK(real().errno_value() == ENOENT);
}

TEST_CASE("real libcomedi: doorbench record and devices without /dev/comedi0",
          "[comedi][real][cli]") {
  if (std::filesystem::exists("/dev/comedi0")) {
    WARN("this machine has /dev/comedi0: the no-device checks do not apply");
    return;
  }
  TempDir dir("comedi_real_cli");
  const auto out = dir / "out.txt", err = dir / "err.txt";
  auto run = [&](const std::string& args) {
    const std::string command = "env -u DOORBENCH_COMEDI_LIBRARY '" DOORBENCH_EXECUTABLE "' " +
                                args + " > '" + out.string() + "' 2> '" + err.string() + "'";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  auto text = [](const std::filesystem::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  CHECK(run("record --rig '" DOORBENCH_SOURCE_DIR "/rigs/reference-bench.toml' --duration-s 1 "
            "--out '" +
            (dir / "s.h5").string() + "'") == 1);
  CHECK_THAT(text(err), Contains("doorbench: /dev/comedi0: cannot open the comedi device: No such "
                                 "file or directory"));
  CHECK(!std::filesystem::exists(dir / "s.h5"));

  CHECK(run("devices") == 0);
  CHECK_THAT(text(out), Contains("through libcomedi (linked)"));
  CHECK_THAT(text(out), Contains("no comedi devices: /dev/comedi* does not exist"));
  CHECK_THAT(text(out), Contains("cDAQ-9172 has no comedi driver"));
}

TEST_CASE("emulator conversions agree with the real libcomedi's", "[comedi][real]") {
  comedi_range range{-5.0, 5.0, UNIT_volt};
  for (lsampl_t data : {0u, 1u, 1000u, 32767u, 32768u, 65534u, 65535u}) {
    const double r = real().to_phys(data, &range, 65535);
    const double e = emulated().to_phys(data, &range, 65535);
    INFO("data " << data);
    CHECK(std::isnan(r) == std::isnan(e));
    if (!std::isnan(r)) CHECK(e == Approx(r).epsilon(1e-15));
  }

  // One calibration, built by hand, through both libraries' softcal lookup and evaluation.
  comedi_polynomial_t cubic{{0.0021, 3.05e-4, 1.2e-11, -4.0e-15}, 32767.5, 3};
  comedi_polynomial_t line{{-10.0, 3.0e-4, 0, 0}, 0.0, 1};
  unsigned channel3 = 3, range1 = 1;
  comedi_calibration_setting_t settings[2]{};
  settings[0].subdevice = 0;
  settings[0].channels = &channel3;
  settings[0].num_channels = 1;
  settings[0].ranges = &range1;
  settings[0].num_ranges = 1;
  settings[0].soft_calibration.to_phys = &cubic;
  settings[1].subdevice = 0;  // every channel and range
  settings[1].soft_calibration.to_phys = &line;
  char name[] = "test";
  comedi_calibration_t calibration{name, name, settings, 2};
  for (const auto& [channel, range_index] :
       {std::pair{3u, 1u}, std::pair{3u, 0u}, std::pair{0u, 1u}}) {
    comedi_polynomial_t from_real{}, from_emulator{};
    const int r = real().get_softcal_converter(0, channel, range_index, COMEDI_TO_PHYSICAL,
                                               &calibration, &from_real);
    const int e = emulated().get_softcal_converter(0, channel, range_index, COMEDI_TO_PHYSICAL,
                                                   &calibration, &from_emulator);
    INFO("channel " << channel << " range " << range_index);
    REQUIRE(r == 0);
    REQUIRE(e == 0);
    CHECK(from_real.order == from_emulator.order);
    CHECK(from_real.expansion_origin == from_emulator.expansion_origin);
    for (lsampl_t data : {0u, 100u, 32767u, 50000u, 65535u}) {
      CHECK(emulated().to_physical(data, &from_emulator) ==
            Approx(real().to_physical(data, &from_real)).epsilon(1e-14));
    }
  }
  // No setting for subdevice 1: both refuse.
  comedi_polynomial_t none{};
  CHECK(real().get_softcal_converter(1, 0, 0, COMEDI_TO_PHYSICAL, &calibration, &none) < 0);
  CHECK(emulated().get_softcal_converter(1, 0, 0, COMEDI_TO_PHYSICAL, &calibration, &none) < 0);
}

TEST_CASE("rigs/reference-bench.toml parses: the study's sensors on an NI M-series card",
          "[comedi][rig]") {
  const auto rig = doorbench::read_rig_file(DOORBENCH_SOURCE_DIR "/rigs/reference-bench.toml");
  CHECK(rig.daq_backend == "comedi");
  CHECK(rig.daq_device == "/dev/comedi0");
  REQUIRE(rig.channels.size() == 3);
  CHECK(rig.channels[0].sensor == "load_cell");
  CHECK(rig.channels[1].sensor == "inclinometer");
  CHECK(rig.channels[2].sensor == "gyroscope");
  for (const auto& channel : rig.channels) {
    CHECK(channel.backend == "comedi");
    CHECK(!channel.aref.empty());
  }
  CHECK(rig.daq_start_trigger.empty());
  REQUIRE(rig.triggers.size() >= 1);
}
