// Live limit warnings in `doorbench record` (issue 21, item 4): on the built-in rig the
// physical reference door falls open faster than the gyroscope's ±100 °/s, so its "rate"
// channel sits at its limit during the openings. Recorded with stderr on a pseudo-terminal
// (the live status display), the status line and the summary must name the channel and the
// time at the limit; the limit watcher's model is checked on its own too.
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <regex>
#include <string>

#include "app/limit_watcher.h"
#include "tests/support/temp_dir.h"

using namespace doorbench;

namespace {

// Runs doorbench with stdout and stderr on a pseudo-terminal; returns what it wrote there
// and its exit status.
std::string run_with_terminal_output(const std::string& args, int& status) {
  int master = -1;
  const pid_t child = ::forkpty(&master, nullptr, nullptr, nullptr);
  if (child < 0) return "";
  if (child == 0) {
    ::execl("/bin/sh", "sh", "-c", (std::string("'" DOORBENCH_EXECUTABLE "' ") + args).c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::string output;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(master, buffer, sizeof buffer);
    if (n <= 0) break;  // EIO once the child closed the terminal
    output.append(buffer, std::size_t(n));
  }
  int wait_status = 0;
  ::waitpid(child, &wait_status, 0);
  ::close(master);
  status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
  return output;
}

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

TEST_CASE("record on a rig that clips: the live status line and the summary name the channel",
          "[record][limits][cli]") {
  testing::TempDir dir("record_limits");
  const std::string session = (dir / "clipping.h5").string();
  int status = -1;
  const std::string output =
      run_with_terminal_output("record --out '" + session + "' --duration-s 4", status);
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
  CHECK(total_s > 0.05);
  CHECK(total_s < 4.0);
  // The physical door's first opening saturates about 1.2 s in (tests/simulated_session.h);
  // the time is the status call's that saw it, and the unpaced simulated bench makes few.
  CHECK(first_s > 0.5);
  CHECK(first_s <= 4.0);
}
