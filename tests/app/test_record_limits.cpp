// Live limit warnings in `doorbench record`: on the built-in rig the
// physical reference door falls open faster than the gyroscope's ±100 °/s, so its "rate"
// channel sits at its limit during the openings. Recorded with stderr on a pseudo-terminal
// (the live status display), the status line and the summary must name the channel and the
// time at the limit; the limit watcher's model is checked on its own too.
#include <catch2/catch.hpp>
#include <cmath>
#include <regex>
#include <string>

#include "acquisition/session/session_file.h"
#include "app/limit_watcher.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_on_terminal.h"

using namespace doorbench;

namespace {

RecordStatus status_at(double recorded_s, double rate) {
  RecordStatus status;
  status.recorded_s = recorded_s;
  ChannelStatus channel;
  channel.name = "rate";
  channel.unit = "rad/s";
  channel.latest = rate;
  channel.samples = 10;
  status.channels.push_back(channel);
  return status;
}

}  // namespace

TEST_CASE("the limit watcher counts time at a channel's limit from the status calls",
          "[record][limits]") {
  app::LimitWatcher watcher({{"rate", "gyroscope", 1.0, "±100 deg/s"}});
  watcher.update(status_at(0.5, 0.2));
  CHECK(watcher.status_text().empty());
  watcher.update(status_at(1.0, 1.0));   // at the limit: a stretch, 1.0 s first, 0.5 s counted
  watcher.update(status_at(1.5, -1.2));  // still (either sign): 0.5 s more
  CHECK(watcher.status_text() == "; AT LIMIT rate (gyroscope ±100 deg/s) now, 1.0 s so far");
  watcher.update(status_at(2.0, 0.1));  // below: not counted
  watcher.update(status_at(3.0, 1.1));  // a second stretch: 1.0 s more
  watcher.update(status_at(3.3, 1.1));
  CHECK(watcher.status_text() == "; AT LIMIT rate (gyroscope ±100 deg/s) now, 2.3 s so far");
  watcher.update(status_at(4.0, 0.0));
  CHECK(watcher.status_text() == "; AT LIMIT rate (gyroscope ±100 deg/s) 2.3 s so far");
  REQUIRE(watcher.summary().size() == 1);
  CHECK(watcher.summary()[0] ==
        "gyroscope rate at its ±100 deg/s limit for 2.3 s in all, 2 times (first at 1.0 s)");
  // A value at the limit between two statuses counts (the largest since the previous one).
  app::LimitWatcher between({{"rate", "gyroscope", 1.0, "±100 deg/s"}});
  RecordStatus status = status_at(2.0, 0.3);
  status.channels[0].largest_abs = 1.05;
  between.update(status);
  REQUIRE(between.summary().size() == 1);
  CHECK(between.summary()[0] ==
        "gyroscope rate at its ±100 deg/s limit for 2.0 s in all, 1 time (first at 2.0 s)");
  // A channel the status does not carry is never at its limit.
  app::LimitWatcher other({{"gyro2", "gyroscope", 1.0, "±100 deg/s"}});
  other.update(status_at(1.0, 5.0));
  CHECK(other.summary().empty());
}

TEST_CASE("limit watcher: the summary's times come from every recorded sample",
          "[record][limits]") {
  testing::TempDir dir("limit_measure");
  const auto path = dir / "rate.h5";
  {
    SessionMetadata metadata;
    metadata.rig_name = "limit-test";
    SessionWriter writer(path, metadata);
    ChannelInfo channel;
    channel.name = "rate";
    channel.sensor_kind = "gyroscope";
    channel.raw_type = RawType::kValues;
    channel.raw_unit = "rad/s";
    channel.unit = "rad/s";
    channel.sample_rate_hz = 1000.0;
    // 1 s at 1 kHz: at the limit for samples 200-299 and 600-719 (0.22 s, twice).
    std::vector<double> values(1000, 0.5);
    for (int i = 200; i < 300; ++i) values[i] = 1.75;
    for (int i = 600; i < 720; ++i) values[i] = -1.75;
    writer.append_values(writer.add_channel(channel), values);
    writer.close();
  }
  app::LimitWatcher watcher({{"rate", "gyroscope", 1.7279, "±100 deg/s"}});
  // Live, one status at 1 s that saw the limit counts the whole second...
  watcher.update(status_at(1.0, 1.75));
  REQUIRE(watcher.summary().size() == 1);
  CHECK(watcher.summary()[0] ==
        "gyroscope rate at its ±100 deg/s limit for 1.0 s in all, 1 time (first at 1.0 s)");
  // ...the recorded samples give the exact figures.
  watcher.measure(SessionReader(path));
  REQUIRE(watcher.summary().size() == 1);
  CHECK(watcher.summary()[0] ==
        "gyroscope rate at its ±100 deg/s limit for 0.2 s in all, 2 times (first at 0.2 s)");
}

TEST_CASE("record on a rig that clips: the live status line and the summary name the channel",
          "[record][limits][cli]") {
  testing::TempDir dir("record_limits");
  const std::string session = (dir / "clipping.h5").string();
  int status = -1;
  const std::string output = testing::run_doorbench_terminal_output(
      "record --out '" + session + "' --duration-s 4", status);
  INFO(output);
  REQUIRE(status == 0);
  // The status line, redrawn in place, says the gyroscope's channel is at its limit.
  CHECK(output.find("; AT LIMIT rate (gyroscope ±100 deg/s)") != std::string::npos);
  // The summary: the channel, its range, the time at the limit and when it first was.
  const std::regex summary(
      R"(warning: gyroscope rate at its ±100 deg/s limit for ([0-9.]+) s in all, ([0-9]+) times? \(first at ([0-9.]+) s\))");
  std::smatch m;
  REQUIRE(std::regex_search(output, m, summary));
  const double total_s = std::stod(m[1]), first_s = std::stod(m[3]);
  // The summary counts the recorded samples (LimitWatcher::measure), not status calls: the
  // door saturates the gyroscope only while it swings, and first about 1.2 s in
  // (fixtures/simulated_session.h).
  CHECK(total_s > 0.05);
  CHECK(total_s < 3.0);
  CHECK(first_s > 0.5);
  CHECK(first_s < 2.0);
}
