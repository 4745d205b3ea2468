// The viewer's live view (viewer/live_journal.h): a LiveJournal following a journal that a
// JournalWriter (the recorder's own) writes at the same time, in another thread or byte by
// byte, sees every frame once and in order, waits at a torn last frame, notices the end
// frame and the journal's conversion, and keeps its memory bounded.
#include <stb_image.h>
#include <sys/wait.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <thread>

#include "acquisition/record/journal.h"
#include "fixtures/temp_dir.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/live_journal.h"

using namespace doorbench;
using namespace doorbench::viewer;
namespace fs = std::filesystem;

namespace {

// Joins a thread when the scope ends, however it ends (a failed REQUIRE throws).
struct JoinOnExit {
  explicit JoinOnExit(std::thread& t) : thread(t) {}
  std::thread& thread;
  void join() {
    if (thread.joinable()) thread.join();
  }
  ~JoinOnExit() { join(); }
  JoinOnExit(const JoinOnExit&) = delete;
  JoinOnExit& operator=(const JoinOnExit&) = delete;
};

// Two scan channels at 1 kHz (a load cell calibrated 1 + 2·V with 1 mV per count, and an
// uncalibrated signal), then a polled channel with its latency channel.
JournalHeader live_header() {
  JournalHeader header;
  header.metadata.rig_name = "live bench";
  ChannelInfo force;
  force.name = "force";
  force.sensor_kind = "load_cell";
  force.raw_scale = 1e-3;
  force.unit = "N";
  force.calibration_id = "lc-1";
  force.sample_rate_hz = 1000.0;
  ChannelInfo angle = force;
  angle.name = "angle";
  angle.sensor_kind = "inclinometer";
  angle.unit = "V";
  angle.calibration_id.clear();
  ChannelInfo polled;
  polled.name = "tilt";
  polled.sensor_kind = "inclinometer";
  polled.raw_type = RawType::kValues;
  polled.raw_unit = "deg";
  polled.unit = "deg";
  polled.sample_rate_hz = 0.0;
  ChannelInfo latency = polled;
  latency.name = "tilt_latency";
  latency.sensor_kind = "poll_latency";
  latency.raw_unit = "s";
  latency.unit = "s";
  header.channels = {force, angle, polled, latency};
  doorbench::CalibrationRecord record;
  record.id = "lc-1";
  record.sensor_kind = "load_cell";
  record.unit = "N";
  record.coefficients = {1.0, 2.0};
  record.method = "test";
  header.calibrations = {record};
  header.scan_rate_hz = 1000.0;
  header.session_name = "live.h5";
  header.flush_interval_s = 0.05;
  header.backend = "test";
  return header;
}

constexpr std::size_t kBlock = 10;

std::int32_t count_of(std::size_t channel, std::uint64_t scan) {
  return static_cast<std::int32_t>(channel == 0 ? scan % 5000 : 100000 + scan);
}

// Writes `blocks` blocks of kBlock scans, a polled sample every 4th block, a trigger at
// block 1, stroke start and a fault every 25 blocks, a stop and the end frame.
void write_recording(JournalWriter& journal, std::size_t blocks,
                     std::chrono::microseconds pause = std::chrono::microseconds(0),
                     const std::function<void(std::size_t)>& after_block = {}) {
  journal.append_start(1, 2);
  std::vector<std::int32_t> counts(2 * kBlock);
  for (std::size_t block = 0; block < blocks; ++block) {
    const std::uint64_t first = block * kBlock;
    for (std::size_t c = 0; c < 2; ++c) {
      for (std::size_t s = 0; s < kBlock; ++s) counts[c * kBlock + s] = count_of(c, first + s);
    }
    journal.append_scans(first, kBlock, counts.data(), kBlock);
    if (block % 4 == 0) {
      const std::int64_t t = static_cast<std::int64_t>(first) * 1000000 + 500000;
      const std::int64_t latency = 2000000;
      const double raw = static_cast<double>(block);
      journal.append_timed(2, 1, &t, &latency, &raw);
    }
    if (block == 1) journal.append_event(0.01, "trigger", "", "level");
    if (block % 25 == 0) journal.append_event(first * 1e-3, "stroke_start", "", "opening");
    if (block % 25 == 12) journal.append_event(first * 1e-3, "fault", "force", "overload");
    if (pause.count() > 0) std::this_thread::sleep_for(pause);
    if (after_block) after_block(block);
  }
  journal.append_event(blocks * kBlock * 1e-3, "stop", "", "recording stopped by hand");
  journal.append_end(blocks * kBlock);
}

// Checks that the rings hold scans [first, end) of both channels, once each, in order.
void check_scans(const LiveJournal& live, std::uint64_t first, std::uint64_t end) {
  const SampleRing& force = live.rings().at(0);
  const SampleRing& angle = live.rings().at(1);
  REQUIRE(force.size() == end - first);
  REQUIRE(angle.size() == end - first);
  for (std::size_t i = 0; i < force.size(); ++i) {
    const std::uint64_t scan = first + i;
    INFO("scan " << scan);
    REQUIRE(force.time(i) == Approx(scan * 1e-3).margin(1e-12));
    REQUIRE(force.value(i) == Approx(1.0 + 2.0 * 1e-3 * count_of(0, scan)).epsilon(1e-12));
    REQUIRE(angle.value(i) == Approx(1e-3 * count_of(1, scan)).epsilon(1e-12));
  }
}

void append_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::app);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST_CASE("Live: a journal written by another thread is followed frame by frame",
          "[viewer][live]") {
  testing::TempDir dir("live_thread");
  const fs::path session = dir.path / "live.h5";
  LiveOptions options;
  options.capacity_samples = 100000;
  // The session's name stands for its journal.
  LiveJournal live(session, options);
  CHECK(live.journal_path() == dir.path / "live.h5.journal");
  CHECK(live.poll().frames == 0);
  CHECK(live.state() == LiveState::kWaiting);
  CHECK_THAT(live.status(), Catch::Contains("no journal yet"));

  constexpr std::size_t kBlocks = 300;
  std::atomic<bool> done{false};
  std::exception_ptr writer_error;
  // The scans the follower has read, published after each poll. Every 10 blocks the writer
  // waits until the follower has read them all, so the recording arrives in at least 30
  // polls however the two threads are scheduled (no timing in the test; the 60 s bound
  // only keeps a broken follower from hanging it).
  std::atomic<std::uint64_t> scans_followed{0};
  const auto wait_for_follower = [&](std::size_t block) {
    if ((block + 1) % 10 != 0) return;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (scans_followed.load() < (block + 1) * kBlock &&
           std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  };
  std::thread writer([&] {
    try {
      JournalWriter journal(journal_path_for(session), live_header(), kBlock, 1);
      write_recording(journal, kBlocks, std::chrono::microseconds(300), wait_for_follower);
      journal.close();
      done = true;
    } catch (...) {
      writer_error = std::current_exception();  // reported after the join, not terminate()
    }
  });
  // Joined on every path: a failed REQUIRE or a throwing poll is reported as a failure
  // instead of ending the binary through a joinable std::thread's destructor.
  JoinOnExit join_writer{writer};
  std::size_t polls_with_data = 0, events = 0, timed = 0;
  std::uint64_t scans = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (live.state() != LiveState::kEnded && std::chrono::steady_clock::now() < deadline) {
    const LivePoll poll = live.poll();
    if (poll.frames > 0) ++polls_with_data;
    scans += poll.scans;
    scans_followed = scans;
    events += poll.events;
    timed += poll.timed_samples;
    // Whatever was read so far is a whole prefix: scans 0 .. scans-1, nothing twice.
    if (poll.scans > 0) REQUIRE(live.rings()[0].size() == scans);
    std::this_thread::sleep_for(std::chrono::microseconds(700));
  }
  join_writer.join();
  if (writer_error) std::rethrow_exception(writer_error);
  REQUIRE(done);
  REQUIRE(live.state() == LiveState::kEnded);
  CHECK_THAT(live.status(), Catch::Contains("the recording ended"));
  // It really followed: the recording arrived in many polls, not in one at the end.
  CHECK(polls_with_data >= 30);
  CHECK(scans == kBlocks * kBlock);
  CHECK(live.scans_read() == kBlocks * kBlock);
  check_scans(live, 0, kBlocks * kBlock);
  CHECK(live.latest_time_s() == Approx((kBlocks * kBlock - 1) * 1e-3));

  // Polled samples and their latencies, in physical units, at their own times.
  const SampleRing& tilt = live.rings()[2];
  const SampleRing& latency = live.rings()[3];
  REQUIRE(tilt.size() == kBlocks / 4);
  CHECK(timed == kBlocks / 4);
  REQUIRE(latency.size() == tilt.size());
  for (std::size_t i = 0; i < tilt.size(); ++i) {
    CHECK(tilt.time(i) == Approx(i * 4 * kBlock * 1e-3 + 5e-4));
    CHECK(tilt.value(i) == Approx(4.0 * i));
    CHECK(latency.value(i) == Approx(2e-3));
  }
  // Every event once, in order: trigger, 12 stroke starts, 12 faults, the stop.
  REQUIRE(events == live.events().size());
  REQUIRE(live.events().size() == 1 + 12 + 12 + 1);
  CHECK(live.events()[0].kind == "stroke_start");
  CHECK(live.events()[1].kind == "trigger");
  CHECK(live.events().back().kind == "stop");
  for (std::size_t i = 1; i < live.events().size(); ++i) {
    CHECK(live.events()[i].time_s >= live.events()[i - 1].time_s);
  }
  // Nothing more once it ended.
  CHECK(live.poll().frames == 0);
}

TEST_CASE("Live: a torn frame at the end is waited for, not an error", "[viewer][live]") {
  testing::TempDir dir("live_torn");
  // The whole recording, written once, then handed over to the followed file in pieces
  // that cut frames anywhere (37 bytes at a time, then the rest).
  const fs::path whole = dir.path / "whole.h5.journal";
  {
    JournalWriter journal(whole, live_header(), kBlock, 1);
    write_recording(journal, 40);
    journal.close();
  }
  const std::string bytes = read_bytes(whole);
  const fs::path followed = dir.path / "live.h5.journal";
  LiveJournal live(followed);
  append_bytes(followed, bytes.substr(0, 10));  // the magic, not the header yet
  CHECK(live.poll().frames == 0);
  CHECK(live.state() == LiveState::kWaiting);
  CHECK_THAT(live.status(), Catch::Contains("header is being written"));

  std::size_t written = 10, frames = 0, torn_polls = 0;
  std::uint64_t last_scans = 0;
  while (written < bytes.size()) {
    const std::size_t piece = std::min<std::size_t>(37, bytes.size() - written);
    append_bytes(followed, bytes.substr(written, piece));
    written += piece;
    LivePoll poll;
    REQUIRE_NOTHROW(poll = live.poll());
    frames += poll.frames;
    if (live.has_header()) {
      // Only whole frames are used; the reader waits at the last one's end.
      CHECK(live.valid_bytes() <= written);
      if (live.valid_bytes() < written) {
        ++torn_polls;
        CHECK_THAT(live.stop_reason(), Catch::StartsWith("incomplete"));
        CHECK_THAT(live.status(), !Catch::Contains("waiting at"));
      }
      CHECK(live.rings()[0].size() >= last_scans);
      last_scans = live.rings()[0].size();
    }
  }
  CHECK(torn_polls > 50);
  CHECK(live.valid_bytes() == bytes.size());
  CHECK(live.state() == LiveState::kEnded);
  check_scans(live, 0, 400);
  JournalReader reader(whole);
  JournalFrame frame;
  std::size_t expected_frames = 0;
  while (reader.next(frame)) ++expected_frames;
  CHECK(frames == expected_frames);
  CHECK(live.events().size() == 1 + 2 + 2 + 1);
}

TEST_CASE("Live: damage (not a torn end) is reported and nothing after it is used",
          "[viewer][live]") {
  testing::TempDir dir("live_damage");
  const fs::path whole = dir.path / "whole.h5.journal";
  {
    JournalWriter journal(whole, live_header(), kBlock, 1);
    write_recording(journal, 5);
    journal.close();
  }
  std::string bytes = read_bytes(whole);
  bytes[bytes.size() - 30] ^= 0x10;  // inside the stop event's frame
  const fs::path followed = dir.path / "live.h5.journal";
  append_bytes(followed, bytes);
  LiveJournal live(followed);
  live.poll();
  CHECK(live.state() == LiveState::kRecording);
  CHECK(live.scans_read() == 50);
  CHECK_THAT(live.stop_reason(), Catch::StartsWith("checksum mismatch"));
  CHECK_THAT(live.status(), Catch::Contains("waiting at checksum mismatch in the frame at byte"));

  // A file that is not a journal at all is an error.
  const fs::path other = dir.path / "other.h5.journal";
  append_bytes(other, std::string(200, 'x'));
  LiveJournal wrong(other);
  CHECK_THROWS_WITH(wrong.poll(), Catch::Contains("not a doorbench journal"));
}

TEST_CASE("Live: memory stays bounded, the last samples and events are kept", "[viewer][live]") {
  testing::TempDir dir("live_bounded");
  const fs::path path = dir.path / "long.h5.journal";
  LiveOptions options;
  options.capacity_samples = 1000;
  options.max_events = 5;
  LiveJournal live(path, options);
  JournalWriter journal(path, live_header(), kBlock, 1);
  journal.append_start(1, 2);
  std::vector<std::int32_t> counts(2 * kBlock);
  std::size_t memory_after_first = 0;
  std::uint64_t scan = 0;
  for (std::size_t round = 0; round < 50; ++round) {
    for (std::size_t block = 0; block < 100; ++block, scan += kBlock) {
      for (std::size_t c = 0; c < 2; ++c) {
        for (std::size_t s = 0; s < kBlock; ++s) counts[c * kBlock + s] = count_of(c, scan + s);
      }
      journal.append_scans(scan, kBlock, counts.data(), kBlock);
    }
    journal.append_event(scan * 1e-3, "mark", "", "round " + std::to_string(round));
    live.poll();
    if (round == 0) memory_after_first = live.memory_bytes();
    REQUIRE(live.memory_bytes() <= memory_after_first + 5 * 200);
    REQUIRE(live.rings()[0].capacity() == 1000);
  }
  CHECK(live.scans_read() == 50000);
  CHECK(live.rings()[0].pushed() == 50000);
  check_scans(live, 49000, 50000);
  REQUIRE(live.events().size() == 5);
  CHECK(live.events().front().detail == "round 45");
  CHECK(live.events().back().detail == "round 49");
  // Four rings of 1000 (time, value) pairs and five short events.
  CHECK(live.memory_bytes() < 4 * 1000 * 16 + 5 * 300);
}

TEST_CASE("Live: the plots show the last window_s seconds with the events marked",
          "[viewer][live]") {
  testing::TempDir dir("live_plots");
  const fs::path path = dir.path / "p.h5.journal";
  LiveOptions options;
  options.window_s = 0.5;
  LiveJournal live(path, options);
  std::vector<PlotView> plots;
  CHECK_FALSE(live.update_plots(plots));  // nothing yet
  JournalWriter journal(path, live_header(), kBlock, 1);
  write_recording(journal, 200);  // 2 s
  live.poll();
  REQUIRE(live.update_plots(plots));
  REQUIRE(plots.size() == 4);
  CHECK(plots[0].title == "force");
  CHECK(plots[0].series.at(0)->unit() == "N");
  CHECK(plots[0].x->min == Approx(1.999 - 0.5));
  CHECK(plots[0].x->max == Approx(1.999));
  CHECK(plots[1].x == plots[0].x);  // linked
  // The series holds the window and one sample before it, not the whole ring.
  const Series& force = *plots[0].series[0];
  CHECK(force.size() >= 501);
  CHECK(force.size() <= 502);
  CHECK(force.x(0) < plots[0].x->min);
  CHECK(force.x(1) >= plots[0].x->min);
  CHECK(force.y(force.size() - 1) == Approx(1.0 + 2e-3 * count_of(0, 1999)));
  CHECK(plots[0].y.min < 1.0 + 2e-3 * count_of(0, 1500));
  // Trigger, stroke starts, the stop and force's own fault are markers on force's plot.
  std::size_t faults = 0, stops = 0, triggers = 0;
  for (const Marker& m : plots[0].markers) {
    faults += m.label.starts_with("fault");
    stops += m.label.starts_with("stop");
    triggers += m.label.starts_with("trigger");
  }
  CHECK(faults == 8);
  CHECK(stops == 1);
  CHECK(triggers == 1);
  CHECK(plots[1].markers.size() == plots[0].markers.size() - 8);  // not force's faults
  // No new frame: nothing to rebuild.
  const std::uint64_t revision = plots[0].revision;
  CHECK_FALSE(live.update_plots(plots));
  CHECK(plots[0].revision == revision);
}

TEST_CASE("Live: a journal converted to its session, or removed, is noticed", "[viewer][live]") {
  testing::TempDir dir("live_gone");
  const fs::path session = dir.path / "s.h5";
  LiveJournal live(session);
  {
    JournalWriter journal(journal_path_for(session), live_header(), kBlock, 1);
    write_recording(journal, 3);
    journal.close();
  }
  live.poll();
  CHECK(live.state() == LiveState::kEnded);
  // What record does at the end: the session appears, then the journal is removed.
  append_bytes(session, "session");
  fs::remove(journal_path_for(session));
  live.poll();
  CHECK(live.state() == LiveState::kGone);
  CHECK_THAT(live.status(), Catch::Contains("the journal was converted to " + session.string()));
  CHECK(live.scans_read() == 30);  // what it had read is kept

  // A recording killed and its journal deleted by hand: removed, frames read up to then.
  const fs::path other = dir.path / "t.h5.journal";
  LiveJournal removed(other);
  JournalWriter journal(other, live_header(), kBlock, 1);
  journal.append_start(1, 2);
  removed.poll();
  CHECK(removed.state() == LiveState::kRecording);
  std::vector<std::int32_t> counts(2 * kBlock, 7);
  journal.append_scans(0, kBlock, counts.data(), kBlock);
  fs::remove(other);
  removed.poll();
  CHECK(removed.state() == LiveState::kGone);
  CHECK(removed.scans_read() == kBlock);  // read through the open file after the removal
  CHECK_THAT(removed.status(), Catch::Contains("the journal was removed"));

  // Following a session that is already finished says so.
  LiveJournal finished(session);
  finished.poll();
  CHECK(finished.state() == LiveState::kGone);
  CHECK_THAT(finished.status(), Catch::Contains("is a finished session"));
}

TEST_CASE("Live: options are checked", "[viewer][live]") {
  LiveOptions options;
  CHECK(options.validate().empty());
  options.window_s = 0.0;
  CHECK_THROWS_WITH(LiveJournal("x.h5", options),
                    "live view: window_s must be a positive number of seconds");
  options = {};
  options.capacity_samples = 1;
  CHECK(options.validate() == "capacity_samples must be at least 2");
}

TEST_CASE("view --live draws a journal being written: the last seconds, where they belong",
          "[viewer][live][xvfb]") {
  testing::TempDir dir("live_screenshot");
  const fs::path journal_path = dir.path / "sine.h5.journal";
  // One channel: a 2 N sine at 0.5 Hz, 1 mV per count, 4 s at 1 kHz; a trigger at 2.5 s; no
  // end frame: the recording is still running when the viewer looks.
  JournalHeader header = live_header();
  header.channels.resize(1);
  header.channels[0].calibration_id.clear();
  header.calibrations.clear();
  const auto known = [](double t) { return 2.0 * std::sin(2.0 * std::numbers::pi * 0.5 * t); };
  JournalWriter journal(journal_path, header, 100);
  journal.append_start(1, 2);
  std::vector<std::int32_t> counts(100);
  for (std::uint64_t first = 0; first < 4000; first += 100) {
    for (std::size_t s = 0; s < 100; ++s) {
      counts[s] = static_cast<std::int32_t>(std::lround(1000.0 * known((first + s) * 1e-3)));
    }
    journal.append_scans(first, 100, counts.data(), 100);
  }
  journal.append_event(2.5, "trigger", "", "level");
  journal.sync();

  const fs::path png = dir.path / "live.png";
  const std::string command = std::string("xvfb-run -a -s '-screen 0 1024x768x24' ")
                                  .append(DOORBENCH_EXECUTABLE)
                                  .append(" view --live ")
                                  .append(journal_path.string())
                                  .append(" --window-s 2 --screenshot ")
                                  .append(png.string())
                                  .append(" --width 900 --height 600 >")
                                  .append((dir.path / "out.txt").string())
                                  .append(" 2>")
                                  .append((dir.path / "err.txt").string());
  const int status = std::system(command.c_str());
  std::ifstream err_file(dir.path / "err.txt"), out_file(dir.path / "out.txt");
  std::ostringstream err, out;
  err << err_file.rdbuf();
  out << out_file.rdbuf();
  INFO("stderr: " << err.str());
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  CHECK_THAT(out.str(), Catch::Contains("recording: 3.999 s, 4000 scans, 42 frames, 1 events"));

  const testing::Screenshot shot = testing::load_screenshot(png);
  REQUIRE(shot.width == 900);
  REQUIRE(shot.height == 600);
  const nlohmann::json& info = shot.info;
  REQUIRE(info["layout"] == "live");
  REQUIRE(info["plots"].size() == 1);
  const auto& plot = info["plots"][0];
  REQUIRE(plot["title"] == "force");
  const std::vector<int> rgb = plot["series"][0]["rgb"];
  const std::vector<double> area = plot["area_px"];
  const std::vector<double> xr = plot["x_range"], yr = plot["y_range"];
  // The last 2 s up to the newest sample, the whole amplitude.
  REQUIRE(xr[0] == Approx(1.999));
  REQUIRE(xr[1] == Approx(3.999));
  REQUIRE(yr[0] < -1.99);
  REQUIRE(yr[1] > 1.99);
  REQUIRE(area[2] > 700);

  const testing::PlotGeometry geometry(plot);
  testing::require_curve_drawn_where_it_belongs(shot.rgb.data(), shot.width, geometry, rgb, known);
  const int top = geometry.top();
  // The trigger's marker: a light vertical line at 2.5 s, in the rows where the curve is not.
  const int marker_px = int(std::lround(area[0] + (2.5 - xr[0]) / (xr[1] - xr[0]) * area[2]));
  int light = 0;
  for (int x = marker_px - 1; x <= marker_px + 1; ++x) {
    const unsigned char* p = shot.pixel(x, top + 5);
    if (p[0] > 90 && p[1] > 90 && p[2] > 90) ++light;
  }
  CHECK(light > 0);
}

TEST_CASE("Live: a long window is plotted as min and max per bucket, a spike stays",
          "[viewer][live]") {
  testing::TempDir dir("live_buckets");
  const fs::path path = dir.path / "b.h5.journal";
  LiveOptions options;
  options.window_s = 100.0;  // everything
  options.max_plot_samples = 100;
  LiveJournal live(path, options);
  JournalWriter journal(path, live_header(), 1000);
  journal.append_start(1, 2);
  std::vector<std::int32_t> counts(2 * 1000, 0);
  for (std::uint64_t first = 0; first < 5000; first += 1000) {
    for (std::size_t s = 0; s < 1000; ++s) {
      const std::uint64_t scan = first + s;
      counts[s] =
          scan == 1234 ? 5000 : (scan == 3001 ? -5000 : static_cast<std::int32_t>(scan % 7));
      counts[1000 + s] = static_cast<std::int32_t>(scan);
    }
    journal.append_scans(first, 1000, counts.data(), 1000);
  }
  // A gap of 500 scans: the line breaks there.
  journal.append_scans(5500, 1000, counts.data(), 1000);
  live.poll();
  std::vector<PlotView> plots;
  REQUIRE(live.update_plots(plots));
  const Series& force = *plots[0].series[0];
  CHECK(force.size() <= 100 + 2);
  CHECK(force.size() >= 90);
  double highest = -1e9, lowest = 1e9, at_highest = 0, at_lowest = 0;
  std::size_t nans = 0;
  for (std::size_t i = 0; i < force.size(); ++i) {
    if (std::isnan(force.y(i))) {
      ++nans;
      continue;
    }
    if (i > 0) REQUIRE(force.x(i) >= force.x(i - 1));
    if (force.y(i) > highest) highest = force.y(i), at_highest = force.x(i);
    if (force.y(i) < lowest) lowest = force.y(i), at_lowest = force.x(i);
  }
  // The spike and the dip, each one sample, at their own times (1 + 2 · 1 mV · count).
  CHECK(highest == Approx(1.0 + 2e-3 * 5000));
  CHECK(at_highest == Approx(1.234));
  CHECK(lowest == Approx(1.0 - 2e-3 * 5000));
  CHECK(at_lowest == Approx(3.001));
  CHECK(nans == 1);  // the gap
  // The second channel rises steadily: its last point is the newest sample.
  const Series& angle = *plots[1].series[0];
  // The re-sent buffer: scan 6499 holds count 4999.
  CHECK(angle.y(angle.size() - 1) == Approx(1e-3 * 4999));
  CHECK(angle.x(angle.size() - 1) == Approx(6.499));
  options.max_plot_samples = 3;
  CHECK(options.validate() == "max_plot_samples must be at least 4");
}
