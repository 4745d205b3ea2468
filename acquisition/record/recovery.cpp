#include "acquisition/record/recovery.h"

#include <fcntl.h>
#include <hdf5.h>
#include <stdio.h>  // renameat2
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>

namespace doorbench {

namespace {

// HDF5 1.10 keeps a file whose close failed (e.g. a full disk while converting) in its
// tables and crashes (SIGSEGV) retrying that close when it shuts down at exit. Without
// its atexit hook the process just exits; every SessionWriter and SessionReader closes
// its own file, so nothing relies on the hook. Runs before main(), before HDF5 starts.
[[maybe_unused]] const herr_t kNoHdf5AtExit = H5dont_atexit();

void sync_path(const std::filesystem::path& path, bool folder) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | (folder ? O_DIRECTORY : 0));
  if (fd < 0) return;
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (result != 0 && !folder) {
    throw SessionError(path.string() + ": cannot sync the file: " + std::strerror(error));
  }
}

std::filesystem::path folder_of(const std::filesystem::path& path) {
  return path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
}

// An exclusive, non-blocking flock on `path`, held while the object lives.
class JournalLock {
 public:
  explicit JournalLock(const std::filesystem::path& path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) {
      const int error = errno;
      throw JournalError(path.string() + ": " +
                         (error == ENOENT ? std::string("no such file") : std::strerror(error)));
    }
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      fd_ = -1;
      throw JournalError(path.string() +
                         ": a running recording is writing this journal (it holds it locked); "
                         "not touching it");
    }
  }
  ~JournalLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  JournalLock(const JournalLock&) = delete;
  JournalLock& operator=(const JournalLock&) = delete;

 private:
  int fd_ = -1;
};

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// True when `journal` ends inside its header and no frame follows: the recording died
// while creating it, before any scan.
bool header_incomplete(const std::filesystem::path& journal) {
  try {
    JournalReader reader(journal);
  } catch (const JournalHeaderIncomplete&) {
    return true;
  } catch (const JournalError&) {
    return false;
  }
  return false;
}

// Renames `journal` "JOURNAL.recovered" (or "-2", "-3", ... after it when that exists;
// never replacing a file) and syncs the folder. Returns the new name, or "" and `problem`.
std::filesystem::path keep_journal(const std::filesystem::path& journal, std::string& problem) {
  for (int n = 1; n <= 1000; ++n) {
    std::filesystem::path kept = journal;
    kept += ".recovered";
    if (n > 1) kept += std::string("-").append(std::to_string(n));
    if (::renameat2(AT_FDCWD, journal.c_str(), AT_FDCWD, kept.c_str(), RENAME_NOREPLACE) == 0) {
      sync_path(folder_of(journal), true);
      return kept;
    }
    const int error = errno;
    if (error == EEXIST) continue;
    if ((error == EINVAL || error == ENOSYS) && !std::filesystem::exists(kept)) {
      // A file system without RENAME_NOREPLACE.
      std::error_code failed;
      std::filesystem::rename(journal, kept, failed);
      if (!failed) {
        sync_path(folder_of(journal), true);
        return kept;
      }
      problem = failed.message();
      return {};
    }
    if (error != EINVAL && error != ENOSYS) {
      problem = std::strerror(error);
      return {};
    }
  }
  problem = "1000 recovered copies of it are already there";
  return {};
}

}  // namespace

std::string ConvertResult::brief_report() const {
  char text[512];
  const double seconds = scan_rate_hz > 0 ? static_cast<double>(scans) / scan_rate_hz : 0.0;
  std::snprintf(text, sizeof text, "%s: %llu scans (%.3f s) of %zu channels, %zu events",
                session.c_str(), static_cast<unsigned long long>(scans), seconds, channels, events);
  std::string report = text;
  if (timed_samples > 0) report += ", " + std::to_string(timed_samples) + " polled samples";
  if (gap_scans > 0) {
    report += "; " + std::to_string(gap_scans) + " scans lost to ring overflows (marked as gaps)";
  }
  if (damaged_stretches > 0) {
    report += "; " + std::to_string(damaged_stretches) + " damaged stretch" +
              (damaged_stretches == 1 ? "" : "es") + " of the journal skipped (" +
              std::to_string(damaged_bytes) + " bytes; the first: " + first_damage + "), " +
              std::to_string(damaged_scans) + " scans lost there (marked as gaps)";
  }
  if (!header_repair.empty()) report += "; the journal's header was repaired: " + header_repair;
  if (already_complete) report += "; the session was already complete";
  if (bytes_dropped > 0) {
    report += "; " + std::to_string(bytes_dropped) + " bytes after the last whole block dropped (" +
              drop_reason + ")";
  } else if (!already_complete && damaged_stretches == 0) {
    report += ", nothing dropped";
  }
  if (!kept_journal.empty()) {
    report += "; the journal is kept as " + kept_journal.string() + " (remove it when you like)";
  } else if (!keep_problem.empty()) {
    report += "; the journal could not be renamed (" + keep_problem + ") and is left as " +
              journal.string();
  }
  return report;
}

namespace {

// The header's metadata, with the origin's UTC time (from the start frame, normally the
// first) as the session's start time.
SessionMetadata metadata_with_start_time(const std::filesystem::path& journal,
                                         const JournalHeader& header) {
  SessionMetadata metadata = header.metadata;
  JournalReader first(journal);
  JournalFrame frame;
  for (int n = 0; n < 8 && first.next(frame); ++n) {
    if (frame.type == FrameType::kStart) {
      if (frame.realtime_ns != 0) metadata.start_time_utc = utc_iso8601_ns(frame.realtime_ns);
      break;
    }
  }
  return metadata;
}

// Writes a journal's frames into a session writer, one frame at a time, counting them in
// the result.
class FrameWriter {
 public:
  FrameWriter(const std::filesystem::path& journal, const JournalHeader& header,
              SessionWriter& writer, ConvertResult& result)
      : journal_(journal),
        header_(header),
        writer_(writer),
        result_(result),
        channel_count_(static_cast<int>(scan_channel_count(header))),
        latency_channel_(header.channels.size(), -1),
        last_time_ns_(header.channels.size(), std::numeric_limits<std::int64_t>::min()) {
    for (const ChannelInfo& channel : header.channels) {
      writer.add_channel(channel);
      names_.insert(channel.name);
    }
    for (const CalibrationRecord& record : header.calibrations) {
      writer.add_calibration(record);
    }
    for (std::size_t c = 0; c < header.channels.size(); ++c) {
      for (std::size_t l = 0; l < header.channels.size(); ++l) {
        if (header.channels[l].sensor_kind == "poll_latency" &&
            header.channels[l].name == header.channels[c].name + "_latency") {
          latency_channel_[c] = static_cast<int>(l);
        }
      }
    }
  }

  void write(const JournalFrame& frame) {
    switch (frame.type) {
      case FrameType::kStart:
        result_.start_monotonic_ns = frame.monotonic_ns;
        result_.start_realtime_ns = frame.realtime_ns;
        break;
      case FrameType::kTimed:
        timed(frame);
        break;
      case FrameType::kEnd:
        result_.ended_cleanly = true;
        break;
      case FrameType::kEvent:
        event(frame.event);
        break;
      case FrameType::kScans:
        scans(frame);
        break;
    }
  }

  // A damaged stretch of `bytes` from byte `from` was skipped: the scans the next block
  // shows missing are lost to it (its gap event says so).
  void damaged(std::uint64_t from, std::uint64_t bytes, const std::string& reason) {
    if (result_.damaged_stretches++ == 0) result_.first_damage = reason;
    result_.damaged_bytes += bytes;
    if (!damage_.empty()) damage_ += ", ";
    damage_ += "bytes " + std::to_string(from) + "-" + std::to_string(from + bytes) + " skipped";
  }

  // After the last frame: the fault for unordered samples, the session clock's origin.
  void finish() {
    if (result_.unordered_samples > 0) {
      writer_.add_event({0.0, "fault", "",
                         std::to_string(result_.unordered_samples) +
                             " polled samples dropped: their time was not after the one "
                             "before on their channel"});
      ++result_.events;
    }
    if (result_.start_monotonic_ns >= 0) {
      // Session time t is CLOCK_MONOTONIC origin_monotonic_ns + t·1e9 and UTC
      // origin_utc + t (docs/session-format.md).
      writer_.write_group_attribute("clock", "origin_monotonic_ns",
                                    std::to_string(result_.start_monotonic_ns));
      if (result_.start_realtime_ns != 0) {
        writer_.write_group_attribute("clock", "origin_realtime_ns",
                                      std::to_string(result_.start_realtime_ns));
        writer_.write_group_attribute("clock", "origin_utc",
                                      utc_iso8601_ns(result_.start_realtime_ns));
      }
    }
  }

 private:
  // A polled channel's samples, and their latencies on its latency channel; explicit times
  // stay strictly increasing (a sample not after the one before is dropped and counted).
  void timed(const JournalFrame& frame) {
    times_s_.clear();
    latencies_s_.clear();
    raws_.clear();
    std::int64_t& last = last_time_ns_[frame.channel];
    for (std::size_t i = 0; i < frame.scan_count; ++i) {
      if (frame.time_ns[i] <= last) {
        ++result_.unordered_samples;
        continue;
      }
      last = frame.time_ns[i];
      times_s_.push_back(static_cast<double>(frame.time_ns[i]) * 1e-9);
      latencies_s_.push_back(static_cast<double>(frame.latency_ns[i]) * 1e-9);
      raws_.push_back(frame.raw[i]);
    }
    writer_.append_timed_values(static_cast<int>(frame.channel), times_s_, raws_);
    if (latency_channel_[frame.channel] >= 0) {
      writer_.append_timed_values(latency_channel_[frame.channel], times_s_, latencies_s_);
    }
    result_.timed_samples += times_s_.size();
  }

  // An event naming a channel the session does not have names it in its detail instead.
  void event(SessionEvent event) {
    if (!event.channel.empty() && names_.count(event.channel) == 0) {
      event.detail = "(channel " + event.channel + ") " + event.detail;
      event.channel.clear();
    }
    if (event.kind.empty()) event.kind = "mark";
    writer_.add_event(event);
    ++result_.events;
  }

  void scans(const JournalFrame& frame) {
    if (frame.first_scan < result_.scans) {
      throw JournalError(journal_.string() + ": block at byte " + std::to_string(frame.offset) +
                         " starts at scan " + std::to_string(frame.first_scan) + ", before scan " +
                         std::to_string(result_.scans) + " that the journal already has");
    }
    if (frame.first_scan > result_.scans) fill_gap(frame);
    damage_.clear();
    for (int c = 0; c < channel_count_; ++c) {
      writer_.append_counts(c, std::span<const std::int32_t>(
                                   frame.counts.data() + c * frame.scan_count, frame.scan_count));
    }
    result_.scans += frame.scan_count;
  }

  // Scans the writer never got (ring overflow) before `frame`: the clock is kept, the gap
  // marked by an event and filled with kGapFillCount.
  void fill_gap(const JournalFrame& frame) {
    const std::uint64_t missing = frame.first_scan - result_.scans;
    // No writer falls an hour behind: such a jump is damage, and filling it would write
    // without bound (found by fuzz/journal.cpp).
    const double hour_of_scans = 3600.0 * header_.scan_rate_hz;
    if (static_cast<double>(missing) > hour_of_scans) {
      throw JournalError(journal_.string() + ": block at byte " + std::to_string(frame.offset) +
                         " starts at scan " + std::to_string(frame.first_scan) + ", " +
                         std::to_string(missing) + " scans after the last one the " +
                         "journal has (more than an hour): the journal is damaged");
    }
    const std::string cause =
        damage_.empty() ? std::string("ring buffer overflow") : "damaged journal: " + damage_;
    char detail[400];
    std::snprintf(detail, sizeof detail,
                  "%llu scans from scan %llu lost (%s); their raw values are %d",
                  static_cast<unsigned long long>(missing),
                  static_cast<unsigned long long>(result_.scans), cause.c_str(), kGapFillCount);
    writer_.add_event(
        {static_cast<double>(result_.scans) / header_.scan_rate_hz, "gap", "", detail});
    ++result_.events;
    fill_.assign(static_cast<std::size_t>(std::min<std::uint64_t>(missing, 65536)), kGapFillCount);
    for (std::uint64_t left = missing; left > 0;) {
      const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(left, fill_.size()));
      for (int c = 0; c < channel_count_; ++c) {
        writer_.append_counts(c, std::span<const std::int32_t>(fill_.data(), n));
      }
      left -= n;
    }
    (damage_.empty() ? result_.gap_scans : result_.damaged_scans) += missing;
    result_.scans = frame.first_scan;
  }

  const std::filesystem::path& journal_;
  const JournalHeader& header_;
  SessionWriter& writer_;
  ConvertResult& result_;
  const int channel_count_;
  std::set<std::string> names_;
  std::vector<int> latency_channel_;        // each polled channel's "<name>_latency", -1: none
  std::vector<std::int64_t> last_time_ns_;  // per channel: the last time written
  std::vector<double> times_s_, latencies_s_, raws_;
  std::vector<std::int32_t> fill_;
  std::string damage_;  // the damaged stretches since the last scans frame
};

// The whole session into `partial`, closed.
void write_partial_session(const std::filesystem::path& journal, JournalReader& reader,
                           const std::filesystem::path& partial, const ConvertOptions& options,
                           ConvertResult& result) {
  const JournalHeader& header = reader.header();
  SessionWriter writer(partial, metadata_with_start_time(journal, header), options.writer);
  FrameWriter frames(journal, header, writer, result);
  JournalFrame frame;
  for (;;) {
    while (reader.next(frame)) frames.write(frame);
    const std::uint64_t from = reader.valid_bytes();
    const std::string reason = reader.stop_reason();
    const std::uint64_t skipped = reader.skip_to_next_frame();
    if (skipped == 0) break;  // the rest is the damaged tail
    frames.damaged(from, skipped, reason);
  }
  frames.finish();
  result.header_repair = reader.header_repair();
  result.journal_bytes = reader.file_bytes();
  result.bytes_dropped = reader.bytes_dropped();
  result.drop_reason = reader.stop_reason();
  if (options.closing_events) {
    for (const SessionEvent& event : options.closing_events(result)) {
      writer.add_event(event);
      ++result.events;
    }
  }
  if (options.extras) options.extras(writer);
  writer.close();
}

// The partial session synced and renamed to the session, the folder synced.
void publish_session(const std::filesystem::path& partial, const std::filesystem::path& session) {
  sync_path(partial, false);
  std::error_code error;
  std::filesystem::rename(partial, session, error);
  if (error) {
    throw SessionError(session.string() + ": cannot rename " + partial.string() +
                       " to it: " + error.message());
  }
  sync_path(folder_of(session), true);
}

}  // namespace

ConvertResult convert_journal(const std::filesystem::path& journal,
                              const std::filesystem::path& session, const ConvertOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(session.string() + ": " + problem);
  }
  if (std::filesystem::exists(session)) {
    throw SessionError(session.string() + ": already exists (sessions are never overwritten)");
  }
  JournalReader reader(journal);
  ConvertResult result;
  result.journal = journal;
  result.session = session;
  result.channels = reader.header().channels.size();
  result.scan_rate_hz = reader.header().scan_rate_hz;

  std::filesystem::path partial = session;
  partial += ".partial";
  // A partial file is a conversion that died; whoever converts holds the journal.
  std::filesystem::remove(partial);
  try {
    write_partial_session(journal, reader, partial, options, result);
    publish_session(partial, session);
  } catch (const std::logic_error& error) {
    // The session writer refused what the header describes (a channel's calibration record
    // missing, a bad name): damage, not a misuse (found by fuzz/journal.cpp).
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw JournalError(journal.string() + ": the journal's header does not describe a valid " +
                       "session: " + error.what());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw;
  }
  return result;
}

namespace {

// The session already exists: the recording was killed between the rename of its
// complete session and the journal's removal, if the session holds the journal's scans
// and the journal its end mark; otherwise refused.
ConvertResult check_already_complete(const std::filesystem::path& journal,
                                     const std::filesystem::path& session) {
  JournalReader reader(journal);
  JournalFrame frame;
  std::uint64_t scans = 0;
  bool ended = false;
  do {
    while (reader.next(frame)) {
      if (frame.type == FrameType::kScans) scans = frame.first_scan + frame.scan_count;
      if (frame.type == FrameType::kEnd) ended = true;
    }
  } while (reader.skip_to_next_frame() > 0);
  const SessionReader existing(session);
  // Scans of the first channel on the scan clock (a polled-only session has none).
  const std::size_t has = scan_channel_count(reader.header()) == 0 || existing.channels().empty()
                              ? 0
                              : existing.sample_count(existing.channels().front().name);
  if (!ended || has != scans) {
    throw JournalError(journal.string() + ": " + session.string() +
                       " already exists and does not hold this journal's " + std::to_string(scans) +
                       " scans (it has " + std::to_string(has) +
                       "); move one of them away, or recover with another output path");
  }
  ConvertResult result;
  result.journal = journal;
  result.session = session;
  result.channels = existing.channels().size();
  result.scans = scans;
  result.events = existing.events().size();
  result.scan_rate_hz = reader.header().scan_rate_hz;
  result.ended_cleanly = true;
  result.already_complete = true;
  return result;
}

// The "recovered" event: where from, what was kept and what was lost.
std::vector<SessionEvent> recovered_event(const std::string& journal_name,
                                          const ConvertResult& so_far) {
  std::string detail = "recovered from " + journal_name;
  detail += so_far.ended_cleanly ? " (the recording had ended; its conversion was interrupted)"
                                 : " after the recording was interrupted";
  detail += ": " + std::to_string(so_far.scans) + " scans";
  if (so_far.damaged_stretches > 0) {
    detail += "; " + std::to_string(so_far.damaged_stretches) + " damaged stretches skipped (" +
              std::to_string(so_far.damaged_bytes) + " bytes), " +
              std::to_string(so_far.damaged_scans) + " scans lost there (marked as gaps)";
  }
  if (!so_far.header_repair.empty()) {
    detail += "; the journal's header was repaired: " + so_far.header_repair;
  }
  if (so_far.bytes_dropped > 0) {
    detail += "; " + std::to_string(so_far.bytes_dropped) +
              " bytes after the last whole block dropped (" + so_far.drop_reason + ")";
  }
  const double time_s =
      so_far.scan_rate_hz > 0 ? static_cast<double>(so_far.scans) / so_far.scan_rate_hz : 0.0;
  return {{time_s, "recovered", "", detail}};
}

}  // namespace

ConvertResult recover_session(const std::filesystem::path& file, const RecoverOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(file.string() + ": " + problem);
  }
  std::filesystem::path journal = file;
  if (!ends_with(file.filename().string(), kJournalSuffix)) {
    journal = journal_path_for(file);
    if (!std::filesystem::exists(journal)) {
      throw JournalError(file.string() + ": nothing to recover (" + journal.string() +
                         " does not exist)");
    }
  }
  const JournalLock lock(journal);
  if (header_incomplete(journal)) {
    std::string problem;
    const std::filesystem::path kept = keep_journal(journal, problem);
    throw JournalError(journal.string() +
                       ": the recording died while creating this journal, before its first "
                       "scan; there is nothing to recover" +
                       (kept.empty()
                            ? "; it is left as it is (it could not be renamed: " + problem + ")"
                            : "; it is kept as " + kept.string() + " (remove it when you like)"));
  }
  std::filesystem::path session = options.out;
  if (session.empty()) {
    const std::string name = journal.filename().string();
    if (ends_with(name, kJournalSuffix)) {
      session = journal.parent_path() / name.substr(0, name.size() - std::strlen(kJournalSuffix));
    } else {
      session = journal.parent_path() / JournalReader(journal).header().session_name;
    }
  }
  ConvertResult result;
  if (std::filesystem::exists(session)) {
    result = check_already_complete(journal, session);
  } else {
    ConvertOptions convert;
    convert.writer = options.writer;
    const std::string journal_name = journal.filename().string();
    convert.closing_events = [journal_name](const ConvertResult& so_far) {
      return recovered_event(journal_name, so_far);
    };
    result = convert_journal(journal, session, convert);
  }
  // Kept, under a name that no recording and no recovery takes for unfinished.
  result.kept_journal = keep_journal(journal, result.keep_problem);
  return result;
}

std::vector<std::filesystem::path> find_unfinished_sessions(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> found;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    if (!entry.is_regular_file() || !ends_with(entry.path().filename().string(), kJournalSuffix)) {
      continue;
    }
    const int fd = ::open(entry.path().c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) continue;
    std::array<char, 8> magic{};
    const ssize_t got = ::pread(fd, magic.data(), magic.size(), 0);
    // A journal cut before its magic was complete is ours too (header_incomplete).
    const bool ours =
        got >= 0 && std::memcmp(magic.data(), kJournalMagic, static_cast<std::size_t>(got)) == 0;
    const bool free = ::flock(fd, LOCK_EX | LOCK_NB) == 0;
    ::close(fd);
    if (ours && free) found.push_back(entry.path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

}  // namespace doorbench
