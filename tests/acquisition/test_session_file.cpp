// Session files (acquisition/session/session_file.h, docs/session-format.md): a write–read round
// trip that must be bit-identical across chunk boundaries, time-range slices, explicit
// times, physical values, every error message, and the file read by plain HDF5 tools
// (h5dump and h5py, run as child processes; scripts/install-deps.sh installs them, and
// the tests fail, not skip, without them).
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/session/session_file.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"

using doorbench::testing::read_file;

extern char** environ;

using Catch::Matchers::Contains;
using doorbench::CalibrationRecord;
using doorbench::ChannelInfo;
using doorbench::ChannelSlice;
using doorbench::RawType;
using doorbench::SessionError;
using doorbench::SessionEvent;
using doorbench::SessionMetadata;
using doorbench::SessionReader;
using doorbench::SessionWriter;
using doorbench::SessionWriterOptions;
namespace fs = std::filesystem;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Scratch = doorbench::testing::TempDir;

struct ChildResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs `args` (args[0] looked up on PATH) with output to a file in `scratch`.
ChildResult run_child(const std::vector<std::string>& args, const Scratch& scratch) {
  static int runs = 0;
  const std::string output_file = (scratch / ("child_" + std::to_string(runs++) + ".txt")).string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<std::string> storage = args;
  std::vector<char*> argv;
  for (std::string& arg : storage) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = ::posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ChildResult result;
  if (spawned != 0) {
    result.exit_code = 127;
    result.output = args[0] + ": cannot run (errno " + std::to_string(spawned) + ")";
    return result;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  result.output = read_file(output_file);
  return result;
}

const std::string kPython = "/usr/bin/python3";

// The exception's text, checking that `F` throws exactly an `E`.
template <class E, class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const E& error) {
    return error.what();
  } catch (const std::exception& error) {
    FAIL("threw the wrong exception type: " << error.what());
  }
  FAIL("did not throw");
  return "";
}

template <class T>
bool bit_identical(const std::vector<T>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if constexpr (std::is_same_v<T, double>) {
      if (std::bit_cast<std::uint64_t>(a[i]) != std::bit_cast<std::uint64_t>(b[i])) return false;
    } else {
      if (static_cast<double>(a[i]) != b[i]) return false;
    }
  }
  return true;
}

// ---------------------------------------------------------------------------------------
// A session with every kind of content

// Designated initializers: GCC 12 at -O3 misreports -Wrestrict on `field = "literal"`.
CalibrationRecord load_cell_record() {
  return CalibrationRecord{.id = "loadcell-LC445-0193-2026-11-21",
                           .sensor_kind = "load_cell",
                           .sensor_serial = "LC445-0193",
                           .input_unit = "V",
                           .unit = "N",
                           .coefficients = {1.5, 100.0, 0.25},
                           .standard_uncertainty = 0.12,
                           .method = "multi-point",
                           .date_utc = "2026-11-21T09:00:00Z",
                           .operator_name = "Jörg Meyer",
                           .valid_until_utc = "",
                           .notes = "five weights, up and down"};
}

SessionMetadata sample_metadata() {
  return SessionMetadata{.rig_name = "bench-2",
                         .rig_definition = "name = \"bench-2\"\n" + std::string(4000, '#') +
                                           "\n[clock]\nrate = 1000\n",
                         .operator_name = "Zoë Ångström",
                         .product_id = "DW-900/4711",
                         .start_time_utc = "2026-11-21T10:30:00Z",
                         .software_version = "doorbench 0.1.0",
                         .notes = "first run after service; door squeaks at 30°"};
}

ChannelInfo force_channel() {
  return ChannelInfo{.name = "force",
                     .sensor_kind = "load_cell",
                     .sensor_serial = "LC445-0193",
                     .raw_type = RawType::kCounts,
                     .raw_unit = "counts",
                     .raw_offset = -10.0,
                     .raw_scale = 20.0 / 65536.0,
                     .range_min = -10.0,
                     .range_max = 10.0,
                     .unit = "N",
                     .calibration_id = "loadcell-LC445-0193-2026-11-21",
                     .sample_rate_hz = 1000.0,
                     .first_sample_time_s = 0.25};
}

ChannelInfo angle_channel() {
  return ChannelInfo{.name = "angle",
                     .sensor_kind = "imported",
                     .sensor_serial = "",
                     .raw_type = RawType::kValues,
                     .raw_unit = "rad",
                     .range_min = -kInf,
                     .range_max = kInf,
                     .unit = "rad",
                     .calibration_id = "",
                     .sample_rate_hz = 3000.0,
                     .first_sample_time_s = 0.0001};
}

ChannelInfo marks_channel() {
  return ChannelInfo{.name = "pot",
                     .sensor_kind = "imported",
                     .sensor_serial = "",
                     .raw_type = RawType::kValues,
                     .raw_unit = "V",
                     .raw_offset = 0.5,
                     .raw_scale = 2.0,
                     .unit = "V",
                     .calibration_id = "",
                     .sample_rate_hz = 0.0};
}

constexpr std::size_t kSamples = 5003;
// Uneven pieces: through the buffer, whole chunks straight to the file, and a partial
// chunk at the end (chunk_samples 1000).
const std::vector<std::size_t> kPieces = {1, 999, 2500, 3, 1500};

std::vector<std::int32_t> sample_counts() {
  std::vector<std::int32_t> counts(kSamples);
  for (std::size_t i = 0; i < kSamples; ++i) {
    counts[i] = static_cast<std::int32_t>((i * 2654435761u) % 65536) - 32768;
  }
  counts[0] = std::numeric_limits<std::int32_t>::min();
  counts[999] = std::numeric_limits<std::int32_t>::max();
  counts[1000] = 0;
  return counts;
}

std::vector<double> sample_values() {
  std::vector<double> values(kSamples);
  for (std::size_t i = 0; i < kSamples; ++i) values[i] = std::sin(0.001 * i) / 3.0;
  values[1] = -0.0;
  values[2] = std::numeric_limits<double>::denorm_min();
  values[3] = std::numeric_limits<double>::max();
  values[4] = -kInf;
  values[5] = std::numeric_limits<double>::quiet_NaN();
  return values;
}

const std::vector<double> kPotTimes = {0.0, 0.5, 0.75, 2.0, 2.25, 3.0, 10.0};
const std::vector<double> kPotValues = {1.0, 1.25, -3.5, 0.125, 7.0, 8.5, -1.0};

std::vector<SessionEvent> sample_events() {
  return {{0.25, "trigger", "", "software"},
          {0.5, "stroke_start", "force", "opening"},
          {1.75, "mark", "", "Tür klemmt — ✔"},
          {2.0, "fault", "angle", ""}};
}

void write_sample_session(const fs::path& path, std::size_t chunk_samples = 1000,
                          int deflate_level = 0) {
  SessionWriterOptions options;
  options.chunk_samples = chunk_samples;
  options.deflate_level = deflate_level;
  SessionWriter writer(path, sample_metadata(), options);
  const int force = writer.add_channel(force_channel());
  const int angle = writer.add_channel(angle_channel());
  const int pot = writer.add_channel(marks_channel());
  writer.add_calibration(load_cell_record());
  writer.add_calibration(load_cell_record());  // the same record again: kept once

  const std::vector<std::int32_t> counts = sample_counts();
  const std::vector<double> values = sample_values();
  std::size_t at = 0;
  for (std::size_t piece : kPieces) {
    writer.append_counts(force, std::span(counts).subspan(at, piece));
    writer.append_values(angle, std::span(values).subspan(at, piece));
    at += piece;
  }
  REQUIRE(at == kSamples);
  writer.append_timed_values(pot, std::span(kPotTimes).first(2), std::span(kPotValues).first(2));
  writer.append_timed_values(pot, std::span(kPotTimes).subspan(2, 0),
                             std::span(kPotValues).subspan(2, 0));
  writer.append_timed_values(pot, std::span(kPotTimes).subspan(2),
                             std::span(kPotValues).subspan(2));
  for (const SessionEvent& event : sample_events()) writer.add_event(event);

  const std::vector<double> truth = {0.0, 0.001, 0.002, -1e300};
  writer.write_group_dataset("truth", "time_s", truth);
  writer.write_group_attribute("truth", "about", "noise-free truth — ω in rad/s");
  writer.write_group_dataset("results/fit-1", "residual_N", std::vector<double>{});
  writer.write_group_attribute("results/fit-1", "uses", "channels/force");
  writer.close();
}

}  // namespace

// ---------------------------------------------------------------------------------------

TEST_CASE("session round trip is bit-identical across chunk boundaries", "[session]") {
  Scratch scratch;
  const std::vector<std::pair<std::size_t, int>> variants = {
      {1000, 0}, {16384, 0}, {1, 0}, {1000, 6}};
  for (const auto& [chunk, deflate] : variants) {
    CAPTURE(chunk, deflate);
    const fs::path path = scratch / (std::to_string(chunk) + "_" + std::to_string(deflate) + ".h5");
    write_sample_session(path, chunk, deflate);
    const SessionReader reader(path);
    CHECK(reader.path() == path);

    REQUIRE(reader.sample_count("force") == kSamples);
    const ChannelSlice force = reader.read("force");
    CHECK(force.first_index == 0);
    CHECK(bit_identical(sample_counts(), force.raw));
    const ChannelSlice angle = reader.read("angle");
    CHECK(bit_identical(sample_values(), angle.raw));
    const ChannelSlice pot = reader.read("pot");
    CHECK(bit_identical(kPotValues, pot.raw));
    CHECK(bit_identical(kPotTimes, pot.time_s));
  }
}

TEST_CASE("session metadata, channels, events, calibrations and groups come back", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "s.h5";
  write_sample_session(path);
  const SessionReader reader(path);

  const SessionMetadata expected = sample_metadata();
  const SessionMetadata& metadata = reader.metadata();
  CHECK(metadata.rig_name == expected.rig_name);
  CHECK(metadata.rig_definition == expected.rig_definition);
  CHECK(metadata.operator_name == expected.operator_name);
  CHECK(metadata.product_id == expected.product_id);
  CHECK(metadata.start_time_utc == expected.start_time_utc);
  CHECK(metadata.software_version == expected.software_version);
  CHECK(metadata.notes == expected.notes);

  const std::vector<ChannelInfo> written = {force_channel(), angle_channel(), marks_channel()};
  REQUIRE(reader.channels().size() == written.size());  // in the order they were added
  for (std::size_t i = 0; i < written.size(); ++i) {
    const ChannelInfo& a = written[i];
    const ChannelInfo& b = reader.channels()[i];
    CAPTURE(a.name);
    CHECK(b.name == a.name);
    CHECK(b.sensor_kind == a.sensor_kind);
    CHECK(b.sensor_serial == a.sensor_serial);
    CHECK(b.raw_type == a.raw_type);
    CHECK(b.raw_unit == a.raw_unit);
    CHECK(b.raw_offset == a.raw_offset);
    CHECK(b.raw_scale == a.raw_scale);
    CHECK(b.range_min == a.range_min);
    CHECK(b.range_max == a.range_max);
    CHECK(b.unit == a.unit);
    CHECK(b.calibration_id == a.calibration_id);
    CHECK(b.sample_rate_hz == a.sample_rate_hz);
    CHECK(b.first_sample_time_s == a.first_sample_time_s);
    CHECK(&reader.channel(a.name) == &b);
  }
  CHECK(reader.sample_count("pot") == kPotTimes.size());
  CHECK(reader.start_time_s() == 0.0);  // pot's first time
  CHECK(reader.end_time_s() == 10.0);   // pot's last time

  const std::vector<SessionEvent> events = reader.events();
  const std::vector<SessionEvent> expected_events = sample_events();
  REQUIRE(events.size() == expected_events.size());
  for (std::size_t i = 0; i < events.size(); ++i) {
    CHECK(events[i].time_s == expected_events[i].time_s);
    CHECK(events[i].kind == expected_events[i].kind);
    CHECK(events[i].channel == expected_events[i].channel);
    CHECK(events[i].detail == expected_events[i].detail);
  }

  const std::vector<CalibrationRecord> records = reader.calibrations();
  REQUIRE(records.size() == 1);
  CHECK(doorbench::to_json(records[0]) == doorbench::to_json(load_cell_record()));

  CHECK(reader.group_datasets("truth") == std::vector<std::string>{"time_s"});
  CHECK(bit_identical(std::vector<double>{0.0, 0.001, 0.002, -1e300},
                      reader.read_group_dataset("truth", "time_s")));
  CHECK(reader.read_group_attribute("truth", "about") == "noise-free truth — ω in rad/s");
  CHECK(reader.group_datasets("results").empty());  // fit-1 is a group, not a dataset
  CHECK(reader.group_datasets("results/fit-1") == std::vector<std::string>{"residual_N"});
  CHECK(reader.read_group_dataset("results/fit-1", "residual_N").empty());
  CHECK(reader.read_group_attribute("results/fit-1", "uses") == "channels/force");
}

TEST_CASE("session events beyond one chunk, and a session without samples", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "events.h5";
  {
    SessionWriter writer(path, SessionMetadata{});
    writer.add_channel(force_channel());  // its record never comes, but it has no samples...
    for (int i = 0; i < 2100; ++i) {
      writer.add_event({0.001 * i, "mark", i % 2 ? "force" : "", std::to_string(i)});
    }
    writer.add_calibration(load_cell_record());  // ...and it comes before close()
    writer.close();
  }
  const SessionReader reader(path);
  const std::vector<SessionEvent> events = reader.events();
  REQUIRE(events.size() == 2100);
  CHECK(events[2099].detail == "2099");
  CHECK(events[2099].channel == "force");
  CHECK(events[1024].time_s == 0.001 * 1024);
  CHECK(reader.sample_count("force") == 0);
  CHECK(reader.start_time_s() == 0.0);
  CHECK(reader.end_time_s() == 0.0);
  CHECK(reader.read("force").raw.empty());
  CHECK(reader.metadata().rig_name.empty());
}

TEST_CASE("session time-range slices read exactly the samples inside", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "s.h5";
  write_sample_session(path);
  const SessionReader reader(path);
  const std::vector<std::int32_t> counts = sample_counts();
  // The times the reader reports: first_sample_time_s + i / sample_rate_hz.
  auto time = [](std::size_t i) { return 0.25 + static_cast<double>(i) / 1000.0; };

  SECTION("boundaries are inclusive at both ends") {
    const ChannelSlice slice = reader.read("force", time(995), time(2003));
    CHECK(slice.first_index == 995);
    REQUIRE(slice.raw.size() == 2003 - 995 + 1);
    REQUIRE(slice.time_s.size() == slice.raw.size());
    for (std::size_t i = 0; i < slice.raw.size(); ++i) {
      REQUIRE(slice.raw[i] == counts[995 + i]);
      REQUIRE(slice.time_s[i] == time(995 + i));
    }
  }
  SECTION("just inside the boundaries excludes the boundary samples") {
    const ChannelSlice slice =
        reader.read("force", std::nextafter(time(995), kInf), std::nextafter(time(2003), -kInf));
    CHECK(slice.first_index == 996);
    CHECK(slice.raw.size() == 2002 - 996 + 1);
    CHECK(slice.raw.front() == counts[996]);
    CHECK(slice.raw.back() == counts[2002]);
  }
  SECTION("first and last samples") {
    ChannelSlice slice = reader.read("force", -kInf, time(0));
    CHECK(slice.first_index == 0);
    CHECK(slice.raw == std::vector<double>{static_cast<double>(counts[0])});
    slice = reader.read("force", time(kSamples - 1), 1e300);
    CHECK(slice.first_index == kSamples - 1);
    CHECK(slice.raw == std::vector<double>{static_cast<double>(counts.back())});
    CHECK(reader.read("force").raw.size() == kSamples);
  }
  SECTION("empty ranges") {
    ChannelSlice slice = reader.read("force", time(10) + 1e-5, time(10) + 2e-5);  // between
    CHECK(slice.raw.empty());
    CHECK(slice.time_s.empty());
    CHECK(slice.first_index == 11);
    slice = reader.read("force", time(20), time(10));  // start after end
    CHECK(slice.raw.empty());
    slice = reader.read("force", -1e9, 0.2);  // before the first sample
    CHECK(slice.raw.empty());
    CHECK(slice.first_index == 0);
    slice = reader.read("force", 100.0, kInf);  // after the last
    CHECK(slice.raw.empty());
    CHECK(slice.first_index == kSamples);
  }
  SECTION("explicit times") {
    ChannelSlice slice = reader.read("pot", 0.5, 2.25);
    CHECK(slice.first_index == 1);
    CHECK(slice.time_s == std::vector<double>{0.5, 0.75, 2.0, 2.25});
    CHECK(slice.raw == std::vector<double>{1.25, -3.5, 0.125, 7.0});
    slice = reader.read("pot", 2.1, 2.2);
    CHECK(slice.raw.empty());
    CHECK(slice.first_index == 4);
    slice = reader.read("pot", 9.0);
    CHECK(slice.time_s == std::vector<double>{10.0});
  }
  SECTION("a uniform channel at 3 kHz (1/3000 is not exact)") {
    auto angle_time = [](std::size_t i) { return 0.0001 + static_cast<double>(i) / 3000.0; };
    for (std::size_t first : {std::size_t{1}, std::size_t{999}, std::size_t{3001}}) {
      const ChannelSlice slice = reader.read("angle", angle_time(first), angle_time(first + 7));
      CHECK(slice.first_index == first);
      CHECK(slice.raw.size() == 8);
      CHECK(slice.time_s.front() == angle_time(first));
    }
  }
}

TEST_CASE("session physical values go through the calibration record", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "s.h5";
  write_sample_session(path);
  const SessionReader reader(path);

  const ChannelSlice force = reader.read("force", 0.25, 0.26);
  const std::vector<double> newtons = reader.physical("force", force);
  REQUIRE(newtons.size() == force.raw.size());
  for (std::size_t i = 0; i < newtons.size(); ++i) {
    if (force.raw[i] ==
        doorbench::kGapFillCount) {  // the mark of a lost scan: missing, never a number
      CHECK(std::isnan(newtons[i]));
      continue;
    }
    const double volts = -10.0 + 20.0 / 65536.0 * force.raw[i];
    CHECK_THAT(newtons[i],
               Catch::Matchers::WithinRel(1.5 + 100.0 * volts + 0.25 * volts * volts, 1e-12));
  }
  // Without a calibration record the signal is the physical value.
  const ChannelSlice pot = reader.read("pot");
  CHECK(reader.physical("pot", pot) == std::vector<double>{2.5, 3.0, -6.5, 0.75, 14.5, 17.5, -1.5});
}

TEST_CASE("session writer refuses existing files and unusable options", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "s.h5";
  const std::string p = path.string() + ": ";

  SECTION("sessions are never overwritten") {
    { std::ofstream(path) << "keep me"; }
    CHECK(message_of<SessionError>([&] { SessionWriter writer(path, {}); }) ==
          p + "already exists (sessions are never overwritten)");
    CHECK(read_file(path) == "keep me");
  }
  SECTION("options") {
    SessionWriterOptions options;
    options.chunk_samples = 0;
    CHECK(message_of<std::invalid_argument>([&] { SessionWriter writer(path, {}, options); }) ==
          p + "session chunk_samples must be 1 to 16777216, not 0");
    options.chunk_samples = 10;
    options.deflate_level = 10;
    CHECK(options.validate() == "session deflate_level must be 0 (no compression) to 9, not 10");
    CHECK_FALSE(fs::exists(path));
  }
  SECTION("a folder that does not exist") {
    const fs::path nowhere = scratch / "no-such-folder" / "s.h5";
    CHECK_THAT(message_of<SessionError>([&] { SessionWriter writer(nowhere, {}); }),
               Catch::Matchers::StartsWith(nowhere.string() + ": cannot create the file (HDF5: "));
  }
}

TEST_CASE("session writer errors name the file and the channel", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "s.h5";
  const std::string p = path.string() + ": ";
  SessionWriter writer(path, sample_metadata());
  const int force = writer.add_channel(force_channel());
  const int angle = writer.add_channel(angle_channel());
  const int pot = writer.add_channel(marks_channel());
  const std::vector<std::int32_t> counts = {1, 2, 3};
  const std::vector<double> values = {1.0, 2.0, 3.0};

  SECTION("channels") {
    CHECK(message_of<std::invalid_argument>([&] { writer.add_channel(force_channel()); }) ==
          p + "channel force is added twice");
    ChannelInfo info = angle_channel();
    info.name = "angle 2";
    CHECK(message_of<std::invalid_argument>([&] { writer.add_channel(info); }) ==
          p + "channel name \"angle 2\" must be letters, digits and _ only");
    info = force_channel();
    info.name = "clicks";
    info.calibration_id.clear();
    info.sample_rate_hz = 0;
    CHECK(message_of<std::invalid_argument>([&] { writer.add_channel(info); }) ==
          p + "channel clicks: explicit times (sample_rate_hz 0) need raw_type values, not counts");
    info.sample_rate_hz = -5;
    CHECK(message_of<std::invalid_argument>([&] { writer.add_channel(info); }) ==
          p + "channel clicks: sample_rate_hz must be > 0, or 0 for explicit times");
    info.sample_rate_hz = 100;
    info.range_max = -20;
    CHECK(message_of<std::invalid_argument>([&] { writer.add_channel(info); }) ==
          p + "channel clicks: range_min must be below range_max");
  }
  SECTION("appending to the wrong channel or with the wrong kind") {
    CHECK(message_of<std::invalid_argument>([&] { writer.append_counts(3, counts); }) ==
          p + "append_counts: no channel with index 3 (3 channels)");
    CHECK(message_of<std::invalid_argument>([&] { writer.append_values(-1, values); }) ==
          p + "append_values: no channel with index -1 (3 channels)");
    CHECK(message_of<std::invalid_argument>([&] { writer.append_values(force, values); }) ==
          p + "append_values: channel force holds counts (int32), not values");
    CHECK(message_of<std::invalid_argument>([&] { writer.append_counts(angle, counts); }) ==
          p + "append_counts: channel angle holds values (float64), not counts");
    CHECK(
        message_of<std::invalid_argument>(
            [&] { writer.append_timed_values(angle, values, values); }) ==
        p + "append_timed_values: channel angle has a uniform clock (3000 Hz); use append_values");
    CHECK(message_of<std::invalid_argument>([&] { writer.append_values(pot, values); }) ==
          p + "append_values: channel pot has explicit times (sample_rate_hz 0); use "
              "append_timed_values");
  }
  SECTION("explicit times") {
    CHECK(message_of<std::invalid_argument>([&] {
            writer.append_timed_values(pot, std::vector<double>{0.0, 1.0}, values);
          }) == p + "append_timed_values: channel pot: 2 times for 3 values");
    CHECK(message_of<std::invalid_argument>([&] {
            writer.append_timed_values(pot, std::vector<double>{0.0, 0.1, 0.1}, values);
          }) == p + "append_timed_values: channel pot: times must be strictly increasing, but "
                    "sample 2 at 0.1 s follows 0.1 s");
    writer.append_timed_values(pot, std::vector<double>{0.0, 0.1, 0.2}, values);
    CHECK(message_of<std::invalid_argument>([&] {
            writer.append_timed_values(pot, std::vector<double>{0.15}, std::vector<double>{1.0});
          }) == p + "append_timed_values: channel pot: times must be strictly increasing, but "
                    "sample 3 at 0.15 s follows 0.2 s");
    CHECK(message_of<std::invalid_argument>([&] {
            writer.append_timed_values(pot, std::vector<double>{kInf}, std::vector<double>{1.0});
          }) == p + "append_timed_values: channel pot: time of sample 3 is not finite");
  }
  SECTION("calibration records") {
    CHECK(message_of<std::invalid_argument>([&] { writer.append_counts(force, counts); }) ==
          p + "channel force uses calibration record loadcell-LC445-0193-2026-11-21, which is "
              "not in the session (add_calibration before its samples)");
    CalibrationRecord record = load_cell_record();
    record.unit = "kN";
    CHECK(message_of<std::invalid_argument>([&] { writer.add_calibration(record); }) ==
          p + "channel force has unit \"N\" but its calibration record "
              "loadcell-LC445-0193-2026-11-21 gives \"kN\"");
    record = load_cell_record();
    record.coefficients = {1.0};
    CHECK(message_of<std::invalid_argument>([&] { writer.add_calibration(record); }) ==
          p + "calibration record loadcell-LC445-0193-2026-11-21: coefficients needs at least "
              "offset and gain");
    record = load_cell_record();
    record.id = "a/b";
    CHECK(message_of<std::invalid_argument>([&] { writer.add_calibration(record); }) ==
          p + "calibration record id \"a/b\" cannot name an HDF5 group (no /)");
    writer.add_calibration(load_cell_record());
    record = load_cell_record();
    record.notes = "changed";
    CHECK(message_of<std::invalid_argument>([&] { writer.add_calibration(record); }) ==
          p + "calibration record loadcell-LC445-0193-2026-11-21 is added twice with different "
              "contents");
    writer.append_counts(force, counts);  // now it is there
  }
  SECTION("a channel may be added after others have samples") {
    writer.append_values(angle, values);
    ChannelInfo late = angle_channel();
    late.name = "late";
    const int index = writer.add_channel(late);
    writer.append_values(index, values);
    writer.add_calibration(load_cell_record());
    writer.close();
    CHECK(SessionReader(path).sample_count("late") == 3);
  }
  SECTION("events") {
    CHECK(message_of<std::invalid_argument>([&] {
            writer.add_event({1.0, "mark", "door", ""});
          }) == p + "event \"mark\" at 1 s names channel door, which is not in the session");
    CHECK(message_of<std::invalid_argument>([&] {
            writer.add_event({1.0, "", "", ""});
          }) == p + "event at 1 s: kind is empty");
    CHECK(message_of<std::invalid_argument>([&] {
            writer.add_event({kInf, "mark", "", ""});
          }) == p + "event \"mark\": time is not finite");
  }
  SECTION("groups") {
    const std::vector<double> none;
    CHECK(message_of<std::invalid_argument>([&] {
            writer.write_group_dataset("channels/x", "a", none);
          }) == p + "group channels/x is inside /channels, which the session writes itself");
    CHECK(message_of<std::invalid_argument>(
              [&] { writer.write_group_attribute("/truth", "a", ""); }) ==
          p + "group \"/truth\" must be names separated by / (no leading, trailing or double /, "
              "no . or ..)");
    writer.write_group_dataset("truth", "a", none);
    CHECK(message_of<std::invalid_argument>([&] {
            writer.write_group_dataset("truth", "a", none);
          }) == p + "group truth already has a");
    CHECK(message_of<std::invalid_argument>([&] {
            writer.write_group_dataset("truth/a", "b", none);
          }) == p + "truth/a exists and is not a group");
    writer.write_group_attribute("truth", "about", "x");
    CHECK(message_of<std::invalid_argument>([&] {
            writer.write_group_attribute("truth", "about", "y");
          }) == p + "group truth already has attribute about");
  }
  SECTION("after close") {
    writer.add_calibration(load_cell_record());
    writer.close();
    CHECK(message_of<std::logic_error>([&] { writer.append_counts(force, counts); }) ==
          p + "the session writer is already closed");
    CHECK(message_of<std::logic_error>([&] { writer.close(); }) ==
          p + "the session writer is already closed");
  }
  SECTION("close() names a calibration record that never came") {
    CHECK(message_of<SessionError>([&] { writer.close(); }) ==
          p + "channel force uses calibration record loadcell-LC445-0193-2026-11-21, which is "
              "not in the session (add_calibration before its samples)");
    CHECK(SessionReader(path).channels().size() == 3);  // the file itself is complete
  }
  try {  // so that the destructor's close() succeeds quietly
    writer.add_calibration(load_cell_record());
  } catch (const std::logic_error&) {
  }
}

TEST_CASE("session reader errors name the file", "[session]") {
  Scratch scratch;
  const fs::path good = scratch / "good.h5";
  write_sample_session(good);
  const std::string g = good.string() + ": ";
  const SessionReader reader(good);

  CHECK(message_of<SessionError>([&] { reader.channel("forse"); }) ==
        g + "no channel \"forse\" (channels: force, angle, pot)");
  CHECK(message_of<SessionError>([&] { reader.read("forse"); }) ==
        g + "no channel \"forse\" (channels: force, angle, pot)");
  CHECK(message_of<SessionError>([&] { reader.sample_count("x"); }) ==
        g + "no channel \"x\" (channels: force, angle, pot)");
  CHECK(message_of<std::invalid_argument>([&] { reader.read("force", std::nan(""), 1.0); }) ==
        g + "read force: start_s and end_s must not be NaN");
  CHECK(message_of<SessionError>([&] { reader.group_datasets("results/fit-9"); }) ==
        g + "no group results/fit-9");
  CHECK(message_of<SessionError>([&] { reader.read_group_dataset("truth", "theta"); }) ==
        g + "group truth has no dataset \"theta\"");
  CHECK(message_of<SessionError>([&] { reader.read_group_attribute("truth", "seed"); }) ==
        g + "group truth has no attribute \"seed\"");

  const fs::path missing = scratch / "missing.h5";
  CHECK(message_of<SessionError>([&] { SessionReader r(missing); }) ==
        missing.string() + ": no such file");
  const fs::path text = scratch / "text.h5";
  { std::ofstream(text) << "time_s,force_N\n0,1\n"; }
  CHECK(message_of<SessionError>([&] { SessionReader r(text); }) ==
        text.string() + ": not a doorbench session (not an HDF5 file)");

  // Files doorbench would not write, made with h5py.
  Scratch made;
  const std::string script =
      "import h5py, shutil, sys\n"
      "good, folder = sys.argv[1], sys.argv[2]\n"
      "with h5py.File(folder + '/plain.h5', 'w') as f: f.create_group('channels')\n"
      "with h5py.File(folder + '/other.h5', 'w') as f: f.attrs['format'] = 'other-thing'\n"
      "shutil.copy(good, folder + '/future.h5')\n"
      "with h5py.File(folder + '/future.h5', 'r+') as f: f.attrs['format_version'] = 9\n"
      "shutil.copy(good, folder + '/nocal.h5')\n"
      "with h5py.File(folder + '/nocal.h5', 'r+') as f:\n"
      "    del f['calibrations/loadcell-LC445-0193-2026-11-21']\n"
      "shutil.copy(good, folder + '/nounit.h5')\n"
      "with h5py.File(folder + '/nounit.h5', 'r+') as f: del f['channels/angle'].attrs['unit']\n";
  const std::string folder = (made / "").string();
  const ChildResult python = run_child({kPython, "-c", script, good.string(), folder}, made);
  INFO(python.output);
  REQUIRE(python.exit_code == 0);

  const fs::path plain = made / "plain.h5";
  CHECK(message_of<SessionError>([&] { SessionReader r(plain); }) ==
        plain.string() + ": not a doorbench session (no format attribute)");
  const fs::path other = made / "other.h5";
  CHECK(message_of<SessionError>([&] { SessionReader r(other); }) ==
        other.string() + ": not a doorbench session (format is \"other-thing\")");
  const fs::path future = made / "future.h5";
  CHECK(message_of<SessionError>([&] { SessionReader r(future); }) ==
        future.string() + ": session format version 9 is newer than this doorbench (1)");
  const fs::path nounit = made / "nounit.h5";
  CHECK(message_of<SessionError>([&] { SessionReader r(nounit); }) ==
        nounit.string() + ": /channels/angle lacks attribute unit");
  const fs::path nocal = made / "nocal.h5";
  const SessionReader without(nocal);
  CHECK(without.calibrations().empty());
  CHECK(message_of<SessionError>([&] {
          without.physical("force", without.read("force", 0, 0.3));
        }) == nocal.string() +
                  ": channel force uses calibration record loadcell-LC445-0193-2026-11-21, "
                  "which is not in the session");
}

TEST_CASE("session files read with plain HDF5 tools", "[session]") {
  Scratch scratch;
  const fs::path path = scratch / "s.h5";
  write_sample_session(path);

  SECTION("h5dump (hdf5-tools)") {
    const ChildResult dump = run_child({"h5dump", path.string()}, scratch);
    INFO("h5dump is in hdf5-tools: run scripts/install-deps.sh\n" << dump.output.substr(0, 2000));
    REQUIRE(dump.exit_code == 0);
    CHECK_THAT(dump.output, Contains("GROUP \"force\"") &&
                                Contains("ATTRIBUTE \"sample_rate_hz\"") &&
                                Contains("\"doorbench-session\"") && Contains("H5T_CSET_UTF8") &&
                                Contains("DATASET \"raw\""));
  }
  SECTION("h5py (python3-h5py, Debian's /usr/bin/python3)") {
    const std::string script =
        "import h5py, sys\n"
        "f = h5py.File(sys.argv[1], 'r')\n"
        "raw = f['channels/force/raw']\n"
        "print(len(raw), *raw[:3], raw.dtype)\n"
        "print(*f['channels'])\n"
        "print(f.attrs['format'], f.attrs['format_version'])\n"
        "print(f['channels/force'].attrs['sample_rate_hz'], f['channels/force'].attrs['unit'])\n"
        "print(*f['calibrations/loadcell-LC445-0193-2026-11-21'].attrs['coefficients'])\n"
        "print(f['metadata'].attrs['operator'])\n"
        "print(len(f['metadata/rig_definition'].asstr()[()]))\n"
        "print(*f['events/kind'].asstr()[:])\n"
        "print(f['events/detail'].asstr()[2], f['channels/pot/time_s'][-1])\n";
    const ChildResult python = run_child({kPython, "-c", script, path.string()}, scratch);
    INFO("h5py is python3-h5py for /usr/bin/python3: run scripts/install-deps.sh\n"
         << python.output);
    REQUIRE(python.exit_code == 0);
    const std::vector<std::int32_t> counts = sample_counts();
    std::ostringstream expected;
    expected << kSamples << ' ' << counts[0] << ' ' << counts[1] << ' ' << counts[2] << " int32\n"
             << "force angle pot\n"
             << "doorbench-session 1\n"
             << "1000.0 N\n"
             << "1.5 100.0 0.25\n"
             << "Zoë Ångström\n"
             << sample_metadata().rig_definition.size() << "\n"
             << "trigger stroke_start mark fault\n"
             << "Tür klemmt — ✔ 10.0\n";
    CHECK(python.output == expected.str());
  }
}
