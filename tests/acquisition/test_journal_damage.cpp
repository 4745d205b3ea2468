// Recovery keeps what it cannot read: a journal damaged in its header, its
// frames or its tail, in a dozen ways at seeded places, is recovered with every scan of
// every frame the damage did not touch; the journal is never deleted or rewritten (it is
// renamed "*.journal.recovered"), and what was lost is marked as gaps and counted.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/record/recovery.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using doorbench::testing::read_file;
using namespace doorbench;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kBlock = 7;    // scans per block
constexpr std::size_t kBlocks = 40;  // 280 scans
constexpr std::size_t kHeadBytes = 20;

JournalHeader test_header() {
  JournalHeader header;
  header.metadata.rig_name = "bench";
  header.metadata.operator_name = "P07";
  ChannelInfo a;
  a.name = "a";
  a.sample_rate_hz = 100.0;
  ChannelInfo b = a;
  b.name = "b";
  header.channels = {a, b};
  header.scan_rate_hz = 100.0;
  header.session_name = "s.h5";
  header.flush_interval_s = 0.05;
  header.backend = "test";
  return header;
}

// counts = 1000·channel + scan; an event before every block; an end mark.
std::string journal_bytes(const fs::path& dir) {
  const fs::path path = dir / "original.journal";
  {
    JournalWriter journal(path, test_header(), kBlock);
    journal.append_start(42, 1700000000000000000);
    std::vector<std::int32_t> counts(2 * kBlock);
    for (std::uint64_t block = 0; block < kBlocks; ++block) {
      for (std::size_t c = 0; c < 2; ++c) {
        for (std::size_t s = 0; s < kBlock; ++s) {
          counts[c * kBlock + s] = static_cast<std::int32_t>(1000 * c + block * kBlock + s);
        }
      }
      journal.append_event(static_cast<double>(block) * 0.07, "mark", "", "block");
      journal.append_scans(block * kBlock, kBlock, counts.data(), kBlock);
    }
    journal.append_end(kBlocks * kBlock);
    journal.close();
  }
  return read_file(path);
}

struct Frame {
  std::size_t offset = 0, end = 0;
  bool scans = false;
  std::uint64_t first_scan = 0;
};

// The original's frames, where they are.
std::vector<Frame> frames_of(const fs::path& dir, const std::string& bytes) {
  const fs::path path = dir / "layout.journal";
  std::ofstream(path, std::ios::binary) << bytes;
  JournalReader reader(path);
  std::vector<Frame> frames;
  JournalFrame frame;
  while (reader.next(frame)) {
    if (!frames.empty()) frames.back().end = frame.offset;
    frames.push_back({frame.offset, 0, frame.type == FrameType::kScans, frame.first_scan});
  }
  frames.back().end = bytes.size();
  return frames;
}

// One damage: the damaged bytes, and which original bytes it touched ([from, to)), or
// none (an insertion between frames).
struct Damaged {
  std::string bytes;
  std::size_t from = 0, to = 0;
  bool header = false;   // the header was damaged
  bool refused = false;  // recovery must refuse (several bytes of the header's text)
  bool nothing = false;  // nothing to recover (the header cut)
  bool counted = false;  // the damage must be counted in the report
};

using Damage = std::function<Damaged(const std::string&, const std::vector<Frame>&, std::mt19937&)>;

std::size_t pick(std::mt19937& random, std::size_t from, std::size_t to) {  // [from, to)
  return std::uniform_int_distribution<std::size_t>(from, to - 1)(random);
}

char changed(char byte, std::mt19937& random) {
  return static_cast<char>(byte ^ static_cast<char>(pick(random, 1, 256)));
}

Damaged overwrite(const std::string& bytes, std::size_t at, std::size_t count,
                  std::mt19937& random) {
  Damaged d{bytes, at, at + count};
  for (std::size_t i = at; i < at + count; ++i) d.bytes[i] = changed(d.bytes[i], random);
  return d;
}

void put32(std::string& bytes, std::size_t at, std::uint32_t value) {
  std::memcpy(bytes.data() + at, &value, 4);
}

const Frame& middle_frame(const std::vector<Frame>& frames, std::mt19937& random) {
  return frames[pick(random, 1, frames.size() - 3)];
}

std::size_t json_end(const std::vector<Frame>& frames) {
  return frames.front().offset;
}

using Damages = std::vector<std::pair<std::string, Damage>>;

Damages header_damages() {
  return {
      {"the header's magic",
       [](const std::string& b, const std::vector<Frame>&, std::mt19937& r) {
         Damaged d = overwrite(b, pick(r, 0, 8), 1, r);
         d.header = true;
         return d;
       }},
      {"the header's version field",
       [](const std::string& b, const std::vector<Frame>&, std::mt19937& r) {
         Damaged d = overwrite(b, pick(r, 8, 12), 1, r);
         d.header = true;
         return d;
       }},
      {"the header's length field (the issue's case)",
       [](const std::string& b, const std::vector<Frame>&, std::mt19937& r) {
         Damaged d = overwrite(b, pick(r, 12, 16), 1, r);
         d.header = true;
         return d;
       }},
      {"the header's checksum field",
       [](const std::string& b, const std::vector<Frame>&, std::mt19937& r) {
         Damaged d = overwrite(b, pick(r, 16, 20), 1, r);
         d.header = true;
         return d;
       }},
      {"one flipped bit in the header's text",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         Damaged d{b, 0, 0, true};
         d.from = pick(r, kHeadBytes, json_end(f));
         d.to = d.from + 1;
         d.bytes[d.from] = static_cast<char>(d.bytes[d.from] ^ (1 << pick(r, 0, 8)));
         return d;
       }},
      {"both the length field and the first frame",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         Damaged d = overwrite(b, 12, 1, r);
         const Damaged frame = overwrite(d.bytes, f[0].offset + pick(r, 0, 4), 1, r);
         d.bytes = frame.bytes;
         d.from = f[0].offset;
         d.to = f[0].end;
         d.header = true;
         return d;
       }},
      {"several bytes of the header's text (refused)",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         const std::size_t at = pick(r, kHeadBytes + 10, json_end(f) - 40);
         Damaged d = overwrite(b, at, 2 + pick(r, 0, 20), r);
         d.bytes[at + 1] = changed(d.bytes[at + 1], r);  // two bytes at least
         d.header = d.refused = true;
         return d;
       }},
      {"the header cut (nothing to recover)",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         Damaged d{b.substr(0, pick(r, 1, json_end(f))), 0, b.size(), true, false, true};
         return d;
       }},
  };
}

Damages frame_damages() {
  return {
      {"a flipped bit in a frame",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         const Frame& frame = middle_frame(f, r);
         Damaged d{b, frame.offset, frame.end};
         const std::size_t at = pick(r, frame.offset, frame.end);
         d.bytes[at] = static_cast<char>(d.bytes[at] ^ (1 << pick(r, 0, 8)));
         d.counted = true;
         return d;
       }},
      {"a frame's marker",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         const Frame& frame = middle_frame(f, r);
         Damaged d = overwrite(b, frame.offset + pick(r, 0, 4), 1, r);
         d.from = frame.offset;
         d.to = frame.end;
         d.counted = true;
         return d;
       }},
      {"a frame's length field",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         const Frame& frame = middle_frame(f, r);
         Damaged d{b, frame.offset, frame.end};
         put32(d.bytes, frame.offset + 8, static_cast<std::uint32_t>(pick(r, 0, 1u << 31)));
         d.counted = true;
         return d;
       }},
      {"zeros over several frames",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         Damaged d{b};
         d.from = pick(r, f[1].offset, f[f.size() / 2].offset);
         d.to = d.from + pick(r, 50, 600);
         std::fill(d.bytes.begin() + static_cast<long>(d.from),
                   d.bytes.begin() + static_cast<long>(d.to), '\0');
         d.counted = true;
         return d;
       }},
      {"bytes inserted between two frames",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         const std::size_t at = middle_frame(f, r).offset;
         std::string junk(pick(r, 1, 300), '\0');
         for (char& c : junk) c = static_cast<char>(pick(r, 0, 256));
         Damaged d{b.substr(0, at) + junk + b.substr(at), at, at};
         d.counted = true;
         return d;
       }},
      {"bytes deleted in the middle",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         Damaged d{b};
         d.from = pick(r, f[1].offset, f[f.size() / 2].offset);
         d.to = d.from + pick(r, 1, 400);
         d.bytes.erase(d.from, d.to - d.from);
         d.counted = true;
         return d;
       }},
      {"the tail cut",
       [](const std::string& b, const std::vector<Frame>& f, std::mt19937& r) {
         const std::size_t cut = pick(r, f[f.size() - 6].offset, b.size());
         return Damaged{b.substr(0, cut), cut, b.size()};
       }},
      {"garbage after the tail",
       [](const std::string& b, const std::vector<Frame>&, std::mt19937& r) {
         std::string junk(pick(r, 1, 5000), '\0');
         for (char& c : junk) c = static_cast<char>(pick(r, 0, 256));
         Damaged d{b + junk, b.size(), b.size()};
         d.counted = true;
         return d;
       }},
  };
}

const Damages& damages() {
  static const Damages all = [] {
    Damages both = header_damages();
    for (auto& damage : frame_damages()) both.push_back(std::move(damage));
    return both;
  }();
  return all;
}

// The scans of the original's blocks that the damage did not touch.
std::vector<std::uint64_t> intact_blocks(const std::vector<Frame>& frames, const Damaged& d) {
  std::vector<std::uint64_t> firsts;
  for (const Frame& frame : frames) {
    if (!frame.scans) continue;
    const bool touched = d.from == d.to ? false : frame.end > d.from && frame.offset < d.to;
    if (!touched) firsts.push_back(frame.first_scan);
  }
  return firsts;
}

}  // namespace

TEST_CASE("Recovery: a journal damaged in its header, frames or tail keeps every intact scan",
          "[journal][recovery]") {
  testing::TempDir dir("journal-damage");
  const std::string original = journal_bytes(dir.path);
  const std::vector<Frame> frames = frames_of(dir.path, original);
  REQUIRE(frames.size() == 2 + 2 * kBlocks);
  int cases = 0, refused = 0, repaired_headers = 0, damaged_stretches = 0;
  for (const auto& [name, damage] : damages()) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      std::mt19937 random(seed * 7919u + static_cast<unsigned>(name.size()));
      const Damaged d = damage(original, frames, random);
      INFO(name << ", seed " << seed << " (original bytes " << d.from << "-" << d.to << ")");
      const fs::path folder = dir / ("case" + std::to_string(++cases));
      fs::create_directories(folder);
      const fs::path journal = folder / "s.h5.journal";
      std::ofstream(journal, std::ios::binary) << d.bytes;
      const fs::path kept = folder / "s.h5.journal.recovered";
      if (d.nothing) {
        CHECK_THROWS_WITH(recover_session(journal),
                          journal.string() +
                              ": the recording died while creating this journal, before its "
                              "first scan; there is nothing to recover; it is kept as " +
                              kept.string() + " (remove it when you like)");
        CHECK(read_file(kept) == d.bytes);
        continue;
      }
      if (d.refused) {
        ++refused;
        try {
          recover_session(journal);
          FAIL("recovered a journal whose header's text is damaged in several bytes");
        } catch (const JournalError& error) {
          const std::string message = error.what();
          CHECK_THAT(message,
                     StartsWith(journal.string() + ": the journal's header is damaged (bytes 20-" +
                                std::to_string(json_end(frames)) + ""));
          CHECK_THAT(message, Contains("checksum mismatch, more than one flipped bit); the frames "
                                       "from byte " +
                                       std::to_string(json_end(frames)) + " on check out"));
          CHECK_THAT(message, Contains("the journal is left as it is"));
        }
        CHECK(read_file(journal) == d.bytes);  // untouched, under its own name
        CHECK(!fs::exists(folder / "s.h5"));
        continue;
      }
      const ConvertResult result = recover_session(journal);
      // The journal is kept, byte for byte, and no longer taken for unfinished.
      CHECK(!fs::exists(journal));
      CHECK(result.kept_journal == kept);
      CHECK(read_file(kept) == d.bytes);
      CHECK(find_unfinished_sessions(folder).empty());
      CHECK_THAT(result.brief_report(), Contains("; the journal is kept as " + kept.string() +
                                                 " (remove it when you like)"));
      // Every intact block's scans, sample for sample.
      const SessionReader session(folder / "s.h5");
      const ChannelSlice a = session.read("a"), b = session.read("b");
      REQUIRE(a.raw.size() == b.raw.size());
      CHECK(a.raw.size() == result.scans);
      for (const std::uint64_t first : intact_blocks(frames, d)) {
        INFO("block from scan " << first);
        REQUIRE(first + kBlock <= a.raw.size());
        for (std::uint64_t s = first; s < first + kBlock; ++s) {
          REQUIRE(a.raw[s] == static_cast<double>(s));
          REQUIRE(b.raw[s] == 1000.0 + static_cast<double>(s));
        }
      }
      // A scan is right or marked lost, never wrong.
      std::uint64_t lost = 0;
      for (std::size_t s = 0; s < a.raw.size(); ++s) {
        if (a.raw[s] == static_cast<double>(kGapFillCount)) {
          ++lost;
          CHECK(b.raw[s] == static_cast<double>(kGapFillCount));
        } else {
          REQUIRE(a.raw[s] == static_cast<double>(s));
        }
      }
      CHECK(lost == result.damaged_scans);
      CHECK(result.gap_scans == 0);  // no ring overflow here
      if (d.header) {
        ++repaired_headers;
        CHECK(!result.header_repair.empty());
        CHECK_THAT(result.brief_report(), Contains("; the journal's header was repaired: "));
      }
      if (d.counted) {
        // Damage in the middle or the tail: counted, never silent.
        CHECK(result.damaged_stretches + (result.bytes_dropped > 0 ? 1 : 0) >= 1);
      }
      if (result.damaged_stretches > 0) {
        ++damaged_stretches;
        CHECK_THAT(result.brief_report(), Contains(" of the journal skipped ("));
      }
      if (lost > 0) {
        const std::vector<SessionEvent> events = session.events();
        CHECK(std::any_of(events.begin(), events.end(), [](const SessionEvent& e) {
          return e.kind == "gap" &&
                 e.detail.find("lost (damaged journal: bytes ") != std::string::npos;
        }));
        CHECK_THAT(events.back().detail, Contains(" scans lost there (marked as gaps)"));
      }
    }
  }
  CHECK(cases == 16 * 6);
  CHECK(refused == 6);
  CHECK(repaired_headers == 6 * 6);
  CHECK(damaged_stretches >= 20);
}

TEST_CASE("Recovery: the header's length field damaged, as the issue found it",
          "[journal][recovery]") {
  testing::TempDir dir("journal-damage");
  std::string bytes = journal_bytes(dir.path);
  const std::size_t json = frames_of(dir.path, bytes).front().offset - kHeadBytes;
  put32(bytes, 12, 0x7FFFFFFFu);  // far beyond the file
  const fs::path journal = dir / "s.h5.journal";
  std::ofstream(journal, std::ios::binary) << bytes;
  const ConvertResult result = recover_session(journal);
  CHECK(result.scans == kBlocks * kBlock);
  CHECK(result.header_repair ==
        "its length field (bytes 12-15) said 2147483647 bytes, but the "
        "header's text is " +
            std::to_string(json) + " bytes long (ending at byte " +
            std::to_string(kHeadBytes + json) + ")");
  CHECK(read_file(dir / "s.h5.journal.recovered") == bytes);
  const std::vector<SessionEvent> events = SessionReader(dir / "s.h5").events();
  CHECK(events.back().detail ==
        "recovered from s.h5.journal (the recording had ended; its conversion was interrupted): "
        "280 scans; the journal's header was repaired: " +
            result.header_repair);
}

TEST_CASE("Recovery: no code path deletes a journal", "[journal][recovery]") {
  // Every removal in acquisition/ and app/ that could name a journal: only the recorder
  // removes its own (acquisition/record/): after its session is complete (recorder.cpp),
  // and when its start failed, before any scan (session_recording.cpp).
  const std::regex removal(R"((std::filesystem::|fs::|::)?(remove|unlink|remove_all)\s*\()");
  int recorder_removals = 0;
  for (const char* folder : {"acquisition", "app"}) {
    for (const auto& entry :
         fs::recursive_directory_iterator(fs::path(DOORBENCH_SOURCE_DIR) / folder)) {
      if (entry.path().extension() != ".cpp" && entry.path().extension() != ".h") continue;
      std::ifstream in(entry.path());
      std::string line;
      for (int number = 1; std::getline(in, line); ++number) {
        if (!std::regex_search(line, removal) || line.find("journal") == std::string::npos)
          continue;
        INFO(entry.path().string() << ":" << number << ": " << line);
        const fs::path& file = entry.path();
        CHECK(file.parent_path().filename() == "record");
        CHECK((file.filename() == "recorder.cpp" || file.filename() == "session_recording.cpp"));
        CHECK_THAT(line, Contains("journal_path"));
        ++recorder_removals;
      }
    }
  }
  CHECK(recorder_removals == 2);
}
