// Crash safety (docs/crash-safety.md): the journal's format and its reader's handling of
// torn and damaged tails; real `doorbench record` processes killed with SIGKILL at random
// moments and recovered, checked sample by sample against the deterministic simulated
// bench and for how much was lost; a full disk; Ctrl-C; `doorbench recover`, and the
// recovery `record` does by itself on its next start.
#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "simulated_bench/simulated_bench.h"
#include "tests/support/fake_polled_source.h"
#include "tests/support/files.h"

using doorbench::testing::read_file;

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using namespace doorbench;
namespace fs = std::filesystem;

namespace {

std::int64_t monotonic_ns() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return std::int64_t{now.tv_sec} * 1000000000 + now.tv_nsec;
}

// The built-in rig with a 1.5 s hand cycle (strokes, hence events, within a short
// recording), paced in real time or not.
std::string test_rig_text(bool realtime) {
  std::string text(simulated_dishwasher_rig_text());
  const auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), to);
  };
  replace("cycle_duration_s = 6.0", "cycle_duration_s = 1.5");
  if (realtime) replace("realtime = false", "realtime = true");
  return text;
}

// What the simulated bench produces for the test rig: counts[channel][scan]. Pacing only
// sleeps, so the unpaced bench gives the same samples.
std::vector<std::vector<std::int32_t>> reference_counts(double duration_s) {
  const RigDefinition rig = parse_rig(test_rig_text(false), "test rig", fs::current_path());
  const DoorModel model = simulated_bench::simulated_door_model(rig);
  simulated_bench::SimulatedBench bench(rig, model, duration_s);
  const auto scans = static_cast<std::size_t>(std::llround(duration_s * rig.sample_rate_hz));
  std::vector<std::vector<std::int32_t>> counts(rig.channels.size());
  ScanBlock block(rig.channels.size(), 100);
  bench.start();
  while (counts[0].size() < scans) {
    block.events.clear();
    const std::size_t n = bench.read(block);
    for (std::size_t c = 0; c < counts.size(); ++c) {
      counts[c].insert(counts[c].end(), block.counts[c].begin(), block.counts[c].begin() + n);
    }
  }
  return counts;
}

// The first `scans` of every channel of `session` equal the reference; returns the scans.
std::size_t check_against_reference(const fs::path& session,
                                    const std::vector<std::vector<std::int32_t>>& reference) {
  const SessionReader reader(session);
  const std::vector<ChannelInfo>& channels = reader.channels();
  REQUIRE(channels.size() == reference.size());
  const std::size_t scans = reader.sample_count(channels[0].name);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    INFO(session << " channel " << channels[c].name);
    const ChannelSlice slice = reader.read(channels[c].name);
    REQUIRE(slice.raw.size() == scans);
    REQUIRE(scans <= reference[c].size());
    std::size_t wrong = 0;
    for (std::size_t s = 0; s < scans; ++s) wrong += slice.raw[s] != reference[c][s] ? 1 : 0;
    CHECK(wrong == 0);
  }
  return scans;
}

struct Child {
  pid_t pid = -1;
  fs::path out, err;
};

struct ChildSetup {
  std::optional<rlim_t> file_size_limit;  // RLIMIT_FSIZE, with SIGXFSZ ignored
};

// Starts DOORBENCH_EXECUTABLE `args` in `dir` (stdout/stderr to files there).
Child start_doorbench(const std::vector<std::string>& args, const fs::path& dir,
                      const ChildSetup& setup = {}) {
  static int counter = 0;
  Child child;
  const std::string tag = std::to_string(counter++);
  child.out = dir / ("stdout_" + tag + ".txt");
  child.err = dir / ("stderr_" + tag + ".txt");
  std::vector<std::string> storage = {DOORBENCH_EXECUTABLE};
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& arg : storage) argv.push_back(arg.data());
  argv.push_back(nullptr);
  const std::string out = child.out.string(), err = child.err.string(), cwd = dir.string();
  child.pid = ::fork();
  REQUIRE(child.pid >= 0);
  if (child.pid == 0) {
    const int in_fd = ::open("/dev/null", O_RDONLY);
    const int out_fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in_fd < 0 || out_fd < 0 || err_fd < 0) ::_exit(126);
    if (::dup2(in_fd, 0) < 0 || ::dup2(out_fd, 1) < 0 || ::dup2(err_fd, 2) < 0) ::_exit(126);
    if (::chdir(cwd.c_str()) != 0) ::_exit(126);
    if (setup.file_size_limit) {
      // Both survive exec: the limit, and the ignored signal (so write() fails with EFBIG
      // instead of the signal killing the process).
      const rlimit limit{*setup.file_size_limit, *setup.file_size_limit};
      if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(126);
      ::signal(SIGXFSZ, SIG_IGN);
    }
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return child;
}

// Waits at most `timeout`; returns the exit status, or -SIGNAL.
int wait_child(const Child& child, std::chrono::seconds timeout = std::chrono::seconds(60)) {
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const pid_t done = ::waitpid(child.pid, &status, WNOHANG);
    if (done == child.pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(child.pid, SIGKILL);
      ::waitpid(child.pid, &status, 0);
      FAIL("doorbench did not finish in time; stderr: " << read_file(child.err));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? -WTERMSIG(status) : -1000;
}

// One recording killed at a random moment, and what became of it.
struct KillRun {
  fs::path dir, session;
  Child child;
  double kill_after_s = 0;
  std::int64_t killed_ns = 0;
  bool killed = false;  // false: it finished before its kill time
};

struct KillStats {
  int kills = 0, complete_at_kill = 0, before_journal = 0, header_only = 0, recovered = 0,
      already_complete = 0, finished = 0;
  double max_lost_s = 0;
  std::vector<fs::path> sessions;
};

constexpr double kRecordS = 3.0;
constexpr double kRateHz = 1000.0;
constexpr std::size_t kBlockScans = 10;  // the recorder's default: 10 ms at 1 kHz

// Recovers and checks one killed recording.
void check_killed(const KillRun& run, const std::vector<std::vector<std::int32_t>>& reference,
                  KillStats& stats) {
  INFO("recording killed " << run.kill_after_s
                           << " s after its start; stderr: " << read_file(run.child.err));
  const fs::path journal = journal_path_for(run.session);
  if (!run.killed) {
    ++stats.finished;
    CHECK(!fs::exists(journal));
    CHECK(check_against_reference(run.session, reference) == kRecordS * kRateHz);
    stats.sessions.push_back(run.session);
    return;
  }
  ++stats.kills;
  if (!fs::exists(journal)) {
    // Killed before the journal existed (parsing the rig), or after it was removed.
    if (fs::exists(run.session)) {
      ++stats.complete_at_kill;
      CHECK(check_against_reference(run.session, reference) == kRecordS * kRateHz);
      stats.sessions.push_back(run.session);
    } else {
      ++stats.before_journal;
      CHECK(run.kill_after_s < 1.0);
    }
    return;
  }
  // The clock's start and the scans as the journal has them, before recovery.
  std::int64_t start_ns = -1;
  try {
    JournalReader reader(journal);
    JournalFrame frame;
    while (reader.next(frame)) {
      if (frame.type == FrameType::kStart) start_ns = frame.monotonic_ns;
    }
  } catch (const JournalError& error) {
    // Killed while writing the header: recovery keeps the empty journal, renamed.
    CHECK_THROWS_WITH(recover_session(journal), Contains("before its first scan"));
    CHECK(!fs::exists(journal));
    CHECK(fs::exists(fs::path(journal.string() + ".recovered")));
    ++stats.header_only;
    return;
  }
  const bool session_was_there = fs::exists(run.session);
  const ConvertResult result = recover_session(journal);
  CHECK(!fs::exists(journal));
  CHECK(result.kept_journal == fs::path(journal.string() + ".recovered"));
  CHECK(fs::exists(result.kept_journal));
  CHECK(result.session == run.session);
  const std::size_t scans = check_against_reference(run.session, reference);
  CHECK(scans == result.scans);
  stats.sessions.push_back(run.session);
  if (session_was_there) {
    CHECK(result.already_complete);
    ++stats.already_complete;
    return;
  }
  ++stats.recovered;
  const std::vector<SessionEvent> events = SessionReader(run.session).events();
  REQUIRE(!events.empty());
  CHECK(events.back().kind == "recovered");
  CHECK_THAT(events.back().detail, StartsWith("recovered from " + journal.filename().string()));
  if (start_ns < 0 || result.ended_cleanly) return;  // nothing acquired yet, or all of it
  // The paced bench hands over block k (scans up to k·B) at start + k·B/rate: that many
  // scans were acquired when the kill came. Recovered scans cannot be more (one block of
  // slack for the two clocks' readings) and at most 100 ms fewer.
  const double since_start_s = static_cast<double>(run.killed_ns - start_ns) * 1e-9;
  const auto acquired = std::min<std::size_t>(
      static_cast<std::size_t>(std::floor(since_start_s * kRateHz / kBlockScans)) * kBlockScans,
      static_cast<std::size_t>(kRecordS * kRateHz));
  INFO("acquired " << acquired << " scans when killed, recovered " << scans);
  CHECK(scans <= acquired + kBlockScans);
  const double lost_s = acquired > scans ? (acquired - scans) / kRateHz : 0.0;
  CHECK(lost_s <= 0.1);
  stats.max_lost_s = std::max(stats.max_lost_s, lost_s);
}

// Opens each session with h5py (one Python process) and prints its force channel's length.
void check_with_h5py(const std::vector<fs::path>& sessions, const fs::path& dir) {
  if (sessions.empty()) return;
  const fs::path list = dir / "sessions.txt";
  {
    std::ofstream out(list);
    for (const fs::path& s : sessions) out << s.string() << "\n";
  }
  const std::string command =
      "/usr/bin/python3 -c \"import h5py,sys\nfor p in "
      "open(sys.argv[1]).read().split('\\n')[:-1]:\n"
      "  f=h5py.File(p,'r'); print(len(f['channels/force/raw']), f['events/kind'].asstr()[-1])\" "
      "'" +
      list.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string output;
  char line[512];
  while (std::fgets(line, sizeof line, pipe) != nullptr) output += line;
  const int status = ::pclose(pipe);
  INFO("h5py: " << output);
  REQUIRE(status == 0);
  std::istringstream lines(output);
  std::size_t opened = 0;
  for (std::string text; std::getline(lines, text);) {
    const std::size_t scans = std::stoul(text);
    const SessionReader reader(sessions[opened]);
    CHECK(scans == reader.sample_count("force"));
    ++opened;
  }
  CHECK(opened == sessions.size());
}

void run_kill_test(int kills, int parallel) {
  testing::TempDir dir("crash");
  const fs::path rig = dir.write("paced.toml", test_rig_text(true));
  const auto reference = reference_counts(kRecordS);
  std::random_device device;
  const unsigned seed = device();
  INFO("kill moments from seed " << seed);
  std::mt19937 random(seed);
  // From the start to the recording's last moments and its conversion, each batch's kills
  // spread over that span: the span is cut into as many equal parts as the batch has
  // recordings, and each is killed at a random moment within its own part. Most kills then
  // land in the recording, however slowly a loaded machine starts the processes, and the
  // moments come in order for the loop below.
  constexpr double kFirstKillS = 0.02, kLastKillS = kRecordS + 0.4;
  std::uniform_real_distribution<double> within(0.0, 1.0);
  KillStats stats;
  for (int first = 0; first < kills; first += parallel) {
    const int batch = std::min(kills, first + parallel) - first;
    const double part_s = (kLastKillS - kFirstKillS) / batch;
    std::vector<KillRun> runs;
    for (int k = first; k < first + batch; ++k) {
      KillRun run;
      run.dir = dir / ("kill" + std::to_string(k));
      fs::create_directories(run.dir);
      run.session = run.dir / "s.h5";
      run.kill_after_s = kFirstKillS + (k - first + within(random)) * part_s;
      run.child = start_doorbench({"record", "--rig", rig.string(), "--duration-s",
                                   std::to_string(kRecordS), "--out", run.session.string()},
                                  run.dir);
      runs.push_back(run);
    }
    const auto started = std::chrono::steady_clock::now();
    for (KillRun& run : runs) {
      std::this_thread::sleep_until(started + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                  std::chrono::duration<double>(run.kill_after_s)));
      run.killed_ns = monotonic_ns();
      run.killed = ::kill(run.child.pid, SIGKILL) == 0;
      const int status = wait_child(run.child);
      // Exited by itself (finished before the kill) or killed.
      if (status != -SIGKILL) {
        INFO("stderr: " << read_file(run.child.err));
        CHECK(status == 0);
        run.killed = false;
      }
    }
    for (const KillRun& run : runs) check_killed(run, reference, stats);
  }
  check_with_h5py(stats.sessions, dir.path);
  WARN("kills " << stats.kills << ": recovered " << stats.recovered << " (largest loss "
                << stats.max_lost_s * 1000 << " ms), already complete " << stats.already_complete
                << ", before the journal " << stats.before_journal << ", header only "
                << stats.header_only << ", complete " << stats.complete_at_kill
                << "; finished before the kill " << stats.finished);
  CHECK(stats.kills + stats.finished == kills);
  CHECK(stats.recovered >= kills / 2);  // most kills land in the recording
}

}  // namespace

// ---------------------------------------------------------------------------------------
// The journal's format

namespace {

std::uint32_t crc_of(std::string_view text, std::uint32_t crc = 0) {
  return crc32({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}, crc);
}

// CRC-32 by its definition, bit by bit: reflected polynomial 0xEDB88320, initial value and
// final XOR 0xFFFFFFFF (what journals were written with before zlib computed it).
std::uint32_t crc_by_definition(std::span<const std::uint8_t> bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const std::uint8_t byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
  }
  return ~crc;
}

}  // namespace

TEST_CASE("Journal: CRC-32 is zlib's", "[journal]") {
  // The published check values of CRC-32 (IEEE 802.3).
  CHECK(crc_of("123456789") == 0xCBF43926u);
  CHECK(crc_of("The quick brown fox jumps over the lazy dog") == 0x414FA339u);
  CHECK(crc_of("a") == 0xE8B7BE43u);
  CHECK(crc32({}) == 0u);
  // Continued over pieces, as the frames' CRC (type and length, then the payload).
  CHECK(crc_of("56789", crc_of("1234")) == 0xCBF43926u);
  CHECK(crc_of("", 0xCBF43926u) == 0xCBF43926u);
  // Every byte value, against the definition.
  std::vector<std::uint8_t> bytes(100000);
  std::mt19937 random(22);
  for (std::uint8_t& byte : bytes) byte = static_cast<std::uint8_t>(random());
  CHECK(crc32(bytes) == crc_by_definition(bytes));
}

TEST_CASE("Journal: one written before the CRC came from zlib reads back", "[journal]") {
  // Written by a recorder whose CRC was not zlib's, killed mid-frame (the fuzzer's seed).
  JournalReader reader(DOORBENCH_SOURCE_DIR "/fuzz/corpus/journal/killed-16k.journal");
  CHECK(reader.header().session_name == "s.h5");  // its CRC checked
  JournalFrame frame;
  std::size_t frames = 0;
  while (reader.next(frame)) ++frames;
  // Every frame's CRC matches up to the one the kill cut short.
  CHECK(frames == 45);
  CHECK(reader.valid_bytes() == 16293);
  CHECK(reader.stop_reason() ==
        "incomplete frame at byte 16293 (136 bytes of data announced, 75 present)");
}

namespace {

JournalHeader small_header() {
  JournalHeader header;
  header.metadata.rig_name = "bench";
  header.metadata.operator_name = "Zoë";
  header.metadata.notes = "line 1\nline \"2\"";
  ChannelInfo a;
  a.name = "a";
  a.range_min = -INFINITY;
  a.range_max = INFINITY;
  a.sample_rate_hz = 100.0;
  a.first_sample_time_s = 1e-5;
  ChannelInfo b = a;
  b.name = "b";
  header.channels = {a, b};
  header.scan_rate_hz = 100.0;
  header.session_name = "s.h5";
  header.flush_interval_s = 0.05;
  header.backend = "test";
  return header;
}

// A journal of 10 blocks of 7 scans, counts = 1000·channel + scan, an event per block.
fs::path write_small_journal(const fs::path& dir, bool with_end = true) {
  const fs::path path = dir / "s.h5.journal";
  JournalWriter journal(path, small_header(), 7);
  journal.append_start(123456789);
  std::vector<std::int32_t> counts(2 * 7);
  for (std::uint64_t block = 0; block < 10; ++block) {
    for (std::size_t c = 0; c < 2; ++c) {
      for (std::size_t s = 0; s < 7; ++s) {
        counts[c * 7 + s] = static_cast<std::int32_t>(1000 * c + block * 7 + s);
      }
    }
    journal.append_event(block * 0.07, "mark", block % 2 ? "b" : "",
                         "block " + std::to_string(block));
    journal.append_scans(block * 7, 7, counts.data(), 7);
  }
  if (with_end) journal.append_end(70);
  journal.close();
  return path;
}

}  // namespace

TEST_CASE("Journal: written and read back frame by frame", "[journal]") {
  testing::TempDir dir("journal");
  const fs::path path = write_small_journal(dir.path);
  JournalReader reader(path);
  CHECK(reader.header().metadata.operator_name == "Zoë");
  CHECK(reader.header().metadata.notes == "line 1\nline \"2\"");
  CHECK(reader.header().channels.at(1).name == "b");
  CHECK(reader.header().channels[0].range_min == -INFINITY);
  CHECK(reader.header().channels[0].first_sample_time_s == 1e-5);
  JournalFrame frame;
  REQUIRE(reader.next(frame));
  CHECK(frame.type == FrameType::kStart);
  CHECK(frame.monotonic_ns == 123456789);
  std::size_t scans = 0, events = 0;
  while (reader.next(frame)) {
    if (frame.type == FrameType::kScans) {
      CHECK(frame.first_scan == scans);
      CHECK(frame.counts.at(7 + 3) == static_cast<std::int32_t>(1000 + scans + 3));
      scans += frame.scan_count;
    } else if (frame.type == FrameType::kEvent) {
      CHECK(frame.event.detail == "block " + std::to_string(events++));
    }
  }
  CHECK(scans == 70);
  CHECK(events == 10);
  CHECK(reader.bytes_dropped() == 0);
  CHECK(reader.stop_reason().empty());
}

TEST_CASE("Recovery: a journal cut at any byte of its tail gives every whole block",
          "[journal][recovery]") {
  testing::TempDir dir("journal");
  fs::create_directories(dir / "orig");
  const fs::path original = write_small_journal(dir / "orig", false);
  const std::string bytes = read_file(original);
  // Each frame: 16-byte header; a scans frame 16 + 2·7·4 = 72 bytes of payload.
  const std::size_t scans_frame = 16 + 16 + 56;
  int cuts_inside_frames = 0;
  for (std::size_t cut = bytes.size() - 2 * scans_frame; cut < bytes.size(); cut += 3) {
    INFO("journal cut to " << cut << " of " << bytes.size() << " bytes");
    const fs::path folder = dir / ("cut" + std::to_string(cut));
    fs::create_directories(folder);
    const fs::path journal = folder / "s.h5.journal";
    std::ofstream(journal, std::ios::binary) << bytes.substr(0, cut);
    const ConvertResult result = recover_session(journal);
    const SessionReader session(folder / "s.h5");
    const std::size_t scans = session.sample_count("a");
    CHECK(scans == result.scans);
    CHECK((scans == 63 || scans == 56));  // the last, or the last two, blocks were cut
    const ChannelSlice b = session.read("b");
    for (std::size_t s = 0; s < scans; ++s) REQUIRE(b.raw[s] == 1000.0 + s);
    CHECK_THAT(result.brief_report(),
               StartsWith((folder / "s.h5").string() + ": " + std::to_string(scans) + " scans ("));
    const std::vector<SessionEvent> events = session.events();
    REQUIRE(!events.empty());
    CHECK(events.back().kind == "recovered");
    const std::string said = "recovered from s.h5.journal after the recording was interrupted: " +
                             std::to_string(scans) + " scans";
    if (result.bytes_dropped == 0) {  // cut exactly between two frames
      CHECK_THAT(result.brief_report(), Contains(", nothing dropped"));
      CHECK(events.back().detail == said);
      continue;
    }
    ++cuts_inside_frames;
    CHECK_THAT(result.brief_report(), Contains(" bytes after the last whole block dropped ("));
    CHECK_THAT(events.back().detail, StartsWith(said + "; " + std::to_string(result.bytes_dropped) +
                                                " bytes after the last whole block dropped ("));
  }
  CHECK(cuts_inside_frames > 50);
}

TEST_CASE("Recovery: a damaged byte ends the journal at the block before it",
          "[journal][recovery]") {
  testing::TempDir dir("journal");
  const fs::path journal = write_small_journal(dir.path, false);
  std::string bytes = read_file(journal);
  const std::size_t flip = bytes.size() - 30;  // inside the last block's samples
  bytes[flip] = static_cast<char>(bytes[flip] ^ 0x10);
  std::ofstream(journal, std::ios::binary | std::ios::trunc) << bytes;
  const ConvertResult result = recover_session(dir / "s.h5");  // by the session's name
  CHECK(result.scans == 63);
  CHECK(result.bytes_dropped == 16 + 16 + 56);
  CHECK_THAT(result.drop_reason, StartsWith("checksum mismatch in the frame at byte "));
  CHECK_THAT(result.brief_report(), Contains("88 bytes after the last whole block dropped"));
}

TEST_CASE("Recovery: zeros after the last block (unwritten space after a power loss)",
          "[journal][recovery]") {
  testing::TempDir dir("journal");
  const fs::path journal = write_small_journal(dir.path, false);
  std::ofstream(journal, std::ios::binary | std::ios::app) << std::string(4096, '\0');
  const ConvertResult result = recover_session(journal);
  CHECK(result.scans == 70);
  CHECK(result.bytes_dropped == 4096);
  CHECK_THAT(result.drop_reason, StartsWith("no frame at byte "));
}

TEST_CASE("Recovery: refusals and the cases around a complete session", "[journal][recovery]") {
  testing::TempDir dir("journal");
  SECTION("nothing to recover") {
    CHECK_THROWS_WITH(recover_session(dir / "none.h5"),
                      (dir / "none.h5").string() + ": nothing to recover (" +
                          (dir / "none.h5.journal").string() + " does not exist)");
  }
  SECTION("not a journal") {
    const fs::path file = dir.write("x.h5.journal", "something else entirely, not ours");
    CHECK_THROWS_WITH(recover_session(file), file.string() + ": not a doorbench journal");
    CHECK(find_unfinished_sessions(dir.path).empty());
  }
  SECTION("killed while creating the journal: kept, nothing to recover") {
    const fs::path file = dir.write("x.h5.journal", "DBJRN");
    CHECK(find_unfinished_sessions(dir.path) == std::vector<fs::path>{file});
    CHECK_THROWS_WITH(recover_session(file),
                      file.string() +
                          ": the recording died while creating this journal, "
                          "before its first scan; there is nothing to recover; it is kept as " +
                          file.string() + ".recovered (remove it when you like)");
    CHECK(!fs::exists(file));
    CHECK(read_file(dir / "x.h5.journal.recovered") == "DBJRN");
    CHECK(find_unfinished_sessions(dir.path).empty());
    // A second one of the same name does not replace the first.
    dir.write("x.h5.journal", "DBJRNL\r\n");
    CHECK_THROWS_WITH(recover_session(file), Contains("it is kept as " + file.string() +
                                                      ".recovered-2 (remove it when you like)"));
    CHECK(read_file(dir / "x.h5.journal.recovered") == "DBJRN");
    CHECK(read_file(dir / "x.h5.journal.recovered-2") == "DBJRNL\r\n");
  }
  SECTION("a running recording's journal is left alone") {
    JournalWriter running(dir / "live.h5.journal", small_header(), 7);
    CHECK(find_unfinished_sessions(dir.path).empty());
    CHECK_THROWS_WITH(recover_session(dir / "live.h5.journal"),
                      Contains("a running recording is writing this journal"));
  }
  SECTION("killed after the session was complete, before the journal was removed") {
    const fs::path journal = write_small_journal(dir.path);
    const std::string bytes = read_file(journal);
    convert_journal(journal, dir / "s.h5", {});
    CHECK(read_file(journal) == bytes);  // left as it was
    CHECK(find_unfinished_sessions(dir.path) == std::vector<fs::path>{journal});
    const ConvertResult result = recover_session(journal);
    CHECK(result.already_complete);
    CHECK(result.scans == 70);
    CHECK(!fs::exists(journal));
    CHECK(read_file(dir / "s.h5.journal.recovered") == bytes);
    CHECK_THAT(result.brief_report(),
               Contains("; the session was already complete; the journal is kept as " +
                        (dir / "s.h5.journal.recovered").string() + " (remove it when you like)"));
  }
  SECTION("a different session in the way") {
    const fs::path journal = write_small_journal(dir.path, false);
    convert_journal(journal, dir / "s.h5", {});
    std::ofstream(journal, std::ios::binary | std::ios::app) << "torn";
    fs::resize_file(journal, fs::file_size(journal) - 100);
    CHECK_THROWS_WITH(recover_session(journal),
                      Contains("s.h5 already exists and does not hold this journal's"));
    CHECK(fs::exists(journal));
    RecoverOptions elsewhere;
    elsewhere.out = dir / "other.h5";
    CHECK(recover_session(journal, elsewhere).scans == 63);
  }
}

// ---------------------------------------------------------------------------------------
// Real recordings killed

// The paced bench (realtime = true) acquires in real time, so the test knows how many
// scans had been acquired at the moment of each kill and can check the loss in time.
TEST_CASE("Crash: recordings SIGKILLed at random moments lose nothing they had written",
          "[crash]") {
  run_kill_test(4, 4);
}

TEST_CASE("Crash: 24 recordings SIGKILLed at random moments (slow)", "[crash][slow]") {
  run_kill_test(24, 4);
}

// A mixed recording (the paced simulated bench and a fake polled source counting its
// polls) in a forked child, killed at random moments: every timed sample in the journal's
// valid frames is in the recovered session, the counts run on without a hole, and what
// was lost is at most the last 100 ms. (Forked rather than run as `doorbench record`:
// the polled source is a test's fake; the fork happens while this process runs no other
// thread.)
namespace {

void run_mixed_kill_test(int kills) {
  testing::TempDir dir("crash-mixed");
  const RigDefinition rig = parse_rig(test_rig_text(true), "test rig", fs::current_path());
  std::random_device device;
  const unsigned seed = device();
  INFO("kill moments from seed " << seed);
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> moment(0.15, 1.1);
  constexpr double kMixedS = 1.0;
  int recovered = 0;
  double max_lost_s = 0.0;
  for (int k = 0; k < kills; ++k) {
    const fs::path folder = dir / std::string("m").append(std::to_string(k));
    fs::create_directories(folder);
    const fs::path session = folder / "s.h5";
    const double kill_after_s = moment(random);
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      int code = 0;
      try {
        const DoorModel model = simulated_bench::simulated_door_model(rig);
        simulated_bench::SimulatedBench bench(rig, model, kMixedS);
        testing::FakePolledOptions fake;
        fake.names = {"pa", "pb"};
        fake.counter = true;
        fake.period_s = 0.002;
        testing::FakePolledSource polled(fake);
        RecordSources sources;
        sources.scans = &bench;
        sources.polled = {&polled};
        RecordOptions options;
        options.duration_s = kMixedS;
        options.flush_interval_s = 0.05;
        options.when_ring_full = RingFullPolicy::kDropAndRecordFault;
        record_session(sources, SessionMetadata{}, session, options);
      } catch (...) {
        code = 3;
      }
      ::_exit(code);
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(kill_after_s));
    const std::int64_t killed_ns = monotonic_ns();
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    INFO("killed after " << kill_after_s << " s");
    const fs::path journal = journal_path_for(session);
    if (!WIFSIGNALED(status)) {
      CHECK(WEXITSTATUS(status) == 0);
      CHECK(!fs::exists(journal));
      continue;
    }
    if (!fs::exists(journal)) continue;  // before the journal, or after its removal
    // What the journal holds (everything written before the kill).
    std::int64_t start_ns = -1;
    bool ended = false;
    std::map<std::uint32_t, std::size_t> written;
    double last_s = 0.0;
    try {
      JournalReader reader(journal);
      JournalFrame frame;
      while (reader.next(frame)) {
        if (frame.type == FrameType::kStart) start_ns = frame.monotonic_ns;
        if (frame.type == FrameType::kEnd) ended = true;
        if (frame.type == FrameType::kTimed) {
          written[frame.channel] += frame.scan_count;
          last_s = std::max(last_s, static_cast<double>(frame.time_ns.back()) * 1e-9);
        }
      }
    } catch (const JournalError&) {
      continue;  // killed while writing the header
    }
    const bool complete = fs::exists(session);
    const ConvertResult result = recover_session(journal);
    const SessionReader reader(session);
    std::size_t total = 0;
    for (const std::string name : {"pa", "pb"}) {
      INFO(name);
      const ChannelSlice slice = reader.read(name);
      total += slice.raw.size();
      for (std::size_t i = 0; i < slice.raw.size(); ++i) {
        // No hole (the first polls may precede time 0, the first scan, and are not kept).
        REQUIRE(slice.raw[i] == slice.raw[0] + static_cast<double>(i));
        if (i > 0) REQUIRE(slice.time_s[i] > slice.time_s[i - 1]);
      }
      CHECK(reader.read(std::string(name).append("_latency")).raw.size() == slice.raw.size());
    }
    std::size_t journaled = 0;
    for (const auto& [channel, count] : written) journaled += count;
    CHECK(total == journaled);
    if (complete || ended || start_ns < 0) continue;
    CHECK(result.timed_samples == journaled);
    ++recovered;
    // Polled samples are taken every few ms and written at once, as the DAQ's blocks are:
    // the newest polled sample written is not more than the flush interval behind the
    // newest scan written. (How far both are behind the kill is the writer's lag, checked
    // against 100 ms by the DAQ kill test above; under heavy parallel I/O of the whole
    // suite a polled sample 141 ms older than the kill was seen: docs/crash-safety.md.)
    const double scans_until_s = static_cast<double>(result.scans) / rig.sample_rate_hz;
    INFO("newest scan " << scans_until_s << " s, newest polled sample " << last_s << " s");
    CHECK(last_s >= scans_until_s - 0.1);
    const double polled_until_s =
        std::min(static_cast<double>(killed_ns - start_ns) * 1e-9, kMixedS);
    const double lost_s = polled_until_s - last_s;
    max_lost_s = std::max(max_lost_s, lost_s);
  }
  WARN("mixed recordings: " << recovered << " of " << kills
                            << " kills recovered mid-recording; the polled samples' largest loss "
                            << max_lost_s * 1000 << " ms");
  CHECK(recovered >= kills * 2 / 5);
}

}  // namespace

TEST_CASE("Crash: killed mixed recordings (DAQ and polled) keep every written polled sample",
          "[crash][sources]") {
  run_mixed_kill_test(5);
}

TEST_CASE("Crash: 24 mixed recordings SIGKILLed at random moments (slow)",
          "[crash][sources][slow]") {
  run_mixed_kill_test(24);
}

TEST_CASE(
    "Crash: doorbench record recovers an unfinished session on its next start, and "
    "doorbench recover by hand",
    "[crash][cli]") {
  testing::TempDir dir("crash");
  const fs::path rig = dir.write("paced.toml", test_rig_text(true));
  const auto reference = reference_counts(kRecordS);
  // Two recordings killed, each in its own folder (a recording started in a folder
  // recovers the folder's unfinished sessions first).
  for (const std::string name : {"a", "b"}) {
    fs::create_directories(dir / name);
    const Child child = start_doorbench(
        {"record", "--rig", rig.string(), "--duration-s", "3", "--out", name + "/" + name + ".h5"},
        dir.path);
    // Killed once its journal holds some blocks (a 7 kB header, then 152 bytes per 10 ms).
    const fs::path journal = dir / name / (name + ".h5.journal");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    const auto size = [&] {
      std::error_code no_file;
      const auto bytes = fs::file_size(journal, no_file);
      return no_file ? 0 : bytes;
    };
    while (size() < 20000 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ::kill(child.pid, SIGKILL);
    REQUIRE(wait_child(child) == -SIGKILL);
    REQUIRE(fs::exists(journal));
  }
  // By hand, by the session's name.
  Child recover = start_doorbench({"recover", "a/a.h5"}, dir.path);
  REQUIRE(wait_child(recover) == 0);
  const std::string said = read_file(recover.err);
  CHECK_THAT(said, StartsWith("recovered a/a.h5: "));
  CHECK_THAT(said, Contains(" scans ("));
  CHECK(check_against_reference(dir / "a" / "a.h5", reference) > 100);
  recover = start_doorbench({"recover", "a/a.h5"}, dir.path);
  CHECK(wait_child(recover) == 1);
  CHECK(read_file(recover.err) ==
        "doorbench: a/a.h5: nothing to recover (a/a.h5.journal does not exist)\n");

  // The next recording in b's folder finds b's journal and recovers it first.
  const Child next = start_doorbench(
      {"record", "--duration-s", "0.2", "--out", (dir / "b" / "c.h5").string()}, dir.path);
  REQUIRE(wait_child(next) == 0);
  const std::string next_said = read_file(next.err);
  INFO(next_said);
  CHECK_THAT(next_said,
             StartsWith("found an unfinished session: " + (dir / "b" / "b.h5.journal").string() +
                        "\nrecovered " + (dir / "b" / "b.h5").string() + ": "));
  CHECK(check_against_reference(dir / "b" / "b.h5", reference) > 100);
  CHECK(!fs::exists(dir / "b" / "b.h5.journal"));
  CHECK(fs::exists(dir / "b" / "b.h5.journal.recovered"));  // kept
  CHECK(SessionReader(dir / "b" / "c.h5").sample_count("force") == 200);
}

TEST_CASE("Crash: Ctrl-C ends a recording cleanly with a complete session", "[crash][cli]") {
  testing::TempDir dir("crash");
  const fs::path rig = dir.write("paced.toml", test_rig_text(true));
  const Child child = start_doorbench(
      {"record", "--rig", rig.string(), "--duration-s", "60", "--out", "s.h5"}, dir.path);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  ::kill(child.pid, SIGINT);
  REQUIRE(wait_child(child, std::chrono::seconds(10)) == 0);
  const std::string said = read_file(child.err);
  INFO(said);
  CHECK_THAT(said, Contains("stopped by request after "));
  CHECK_THAT(said, Contains("wrote s.h5: 3 channels, "));
  CHECK(!fs::exists(dir / "s.h5.journal"));
  const auto reference = reference_counts(1.0);
  const std::size_t scans = check_against_reference(dir / "s.h5", reference);
  CHECK(scans > 200);
  CHECK(scans < 1000);
  const std::vector<SessionEvent> events = SessionReader(dir / "s.h5").events();
  REQUIRE(!events.empty());
  CHECK(events.back().kind == "stop");
  check_with_h5py({dir / "s.h5"}, dir.path);
}

namespace {

// A full file system or a file-size limit: the recording stops with a message naming
// the journal, and the journal keeps every block written before.
void check_write_failure(const Child& child, const fs::path& session, const std::string& cause,
                         const fs::path& recovered) {
  REQUIRE(wait_child(child) == 1);
  const std::string said = read_file(child.err);
  INFO(said);
  const fs::path journal = journal_path_for(session);
  CHECK_THAT(said, Contains("doorbench: " + journal.string() + ": cannot write the journal: " +
                            cause + "; the recording stopped after "));
  CHECK_THAT(said, Contains(" written so far are kept in " + journal.string() +
                            " (free space, then: doorbench recover " + journal.string() + ")\n"));
  CHECK(!fs::exists(session));
  REQUIRE(fs::exists(journal));
  RecoverOptions options;
  options.out = recovered;
  const ConvertResult result = recover_session(journal, options);
  const auto reference = reference_counts(60.0);
  const std::size_t scans = check_against_reference(recovered, reference);
  CHECK(scans == result.scans);
  CHECK(scans > 1000);
  check_with_h5py({recovered}, recovered.parent_path());
}

}  // namespace

TEST_CASE("Crash: a file-size limit (EFBIG) stops the recording and keeps what was written",
          "[crash][disk]") {
  testing::TempDir dir("crash");
  const fs::path rig = dir.write("fast.toml", test_rig_text(false));
  ChildSetup setup;
  setup.file_size_limit = 200000;  // about 15 s of the rig's 3 channels at 1 kHz
  const Child child = start_doorbench(
      {"record", "--rig", rig.string(), "--duration-s", "60", "--out", (dir / "s.h5").string()},
      dir.path, setup);
  check_write_failure(child, dir / "s.h5", "File too large", dir / "recovered.h5");
}

TEST_CASE(
    "Crash: a full file system (ENOSPC, a small tmpfs) stops the recording and keeps "
    "what was written",
    "[crash][disk]") {
  testing::TempDir dir("crash");
  const fs::path mount_point = dir / "small";
  fs::create_directories(mount_point);
  if (::mount("tmpfs", mount_point.c_str(), "tmpfs", 0, "size=256k") != 0) {
    WARN("cannot mount a tmpfs here (" << std::strerror(errno)
                                       << "); the full-disk case is covered by the file-size "
                                          "limit test only");
    return;
  }
  struct Unmount {
    fs::path path;
    ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
  } unmount{mount_point};
  const fs::path rig = dir.write("fast.toml", test_rig_text(false));
  const Child child = start_doorbench({"record", "--rig", rig.string(), "--duration-s", "60",
                                       "--out", (mount_point / "s.h5").string()},
                                      dir.path);
  check_write_failure(child, mount_point / "s.h5", "No space left on device", dir / "recovered.h5");
}

TEST_CASE("Crash: a write failure while converting keeps the whole journal", "[crash][disk]") {
  testing::TempDir dir("crash");
  // The journal of 1 s (about 22 kB) fits under the limit; the session, with a 64 kB chunk
  // per channel, does not.
  ChildSetup setup;
  setup.file_size_limit = 100000;
  const fs::path session = dir / "s.h5";
  const Child child =
      start_doorbench({"record", "--duration-s", "1", "--out", session.string()}, dir.path, setup);
  REQUIRE(wait_child(child) == 1);
  const std::string said = read_file(child.err);
  INFO(said);
  const fs::path journal = journal_path_for(session);
  CHECK_THAT(said, Contains("doorbench: " + session.string() + ".partial: "));
  CHECK_THAT(said, Contains("; the recording is kept in " + journal.string() +
                            " (free space, then: doorbench recover " + journal.string() + ")\n"));
  CHECK(!fs::exists(session));
  CHECK(!fs::exists(dir / "s.h5.partial"));
  const ConvertResult result = recover_session(journal);
  CHECK(result.ended_cleanly);
  CHECK(result.scans == 1000);
  CHECK(result.bytes_dropped == 0);
  CHECK(SessionReader(session).sample_count("rate") == 1000);
}
