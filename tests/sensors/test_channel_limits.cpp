// The sensors' limits (sensors/channel_limits.h): which rig channels have one and where, the
// runs of samples at it, and a session's rig read back from its metadata.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "core/units.h"
#include "sensors/channel_limits.h"

using namespace doorbench;

TEST_CASE("channel limits: the inclinometer's and the gyroscope's range less 1 %", "[limits]") {
  const RigDefinition rig =
      parse_rig(simulated_dishwasher_rig_text(), "built-in", std::filesystem::current_path());
  const std::vector<sensors::ChannelLimit> limits = sensors::rig_channel_limits(rig);
  REQUIRE(limits.size() == 2);  // the load cell has none
  CHECK(limits[0].channel == "angle");
  CHECK(limits[0].sensor == "inclinometer");
  CHECK(limits[0].limit == Approx(0.99 * 10.0 * doorbench::kRadPerDeg));
  CHECK(limits[0].range == "±10 deg");
  CHECK(limits[1].channel == "rate");
  CHECK(limits[1].limit == Approx(0.99 * 100.0 * doorbench::kRadPerDeg));
  CHECK(limits[1].range == "±100 deg/s");

  SessionMetadata metadata;
  CHECK(sensors::session_channel_limits(metadata).empty());  // no rig stated
  metadata.rig_definition = "not a rig";
  CHECK(sensors::session_channel_limits(metadata).empty());  // a rig that does not parse
  metadata.rig_definition = std::string(simulated_dishwasher_rig_text());
  CHECK(sensors::session_channel_limits(metadata).size() == 2);
}

TEST_CASE("channel limits: runs of samples at the limit, either sign, NaN not", "[limits]") {
  const double nan = std::nan("");
  const std::vector<double> values = {0.0, 1.0, -1.2, 0.5, nan, 1.0, 0.99, 1.0, 1.0};
  const std::vector<sensors::SampleStretch> runs = sensors::limit_stretches(values, 1.0);
  REQUIRE(runs.size() == 3);
  CHECK(runs[0].begin == 1);
  CHECK(runs[0].end == 3);
  CHECK(runs[1].begin == 5);
  CHECK(runs[1].end == 6);
  CHECK(runs[2].begin == 7);
  CHECK(runs[2].end == 9);  // a run to the last sample
  CHECK(sensors::limit_stretches({}, 1.0).empty());
  CHECK(sensors::limit_stretches({nan, 0.5}, 1.0).empty());
}
