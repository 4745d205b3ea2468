#pragma once
// Turning a recording journal (journal.h) into the HDF5 session: at the normal end of a
// recording, and to recover a recording that was killed, lost power or ran out of disk.
//
// The session is written as "SESSION.partial", flushed, synced and only then renamed to
// its name, so a session file under its own name is always complete. Recovery never
// deletes or rewrites a journal: it renames it "JOURNAL.recovered" (kept until the user
// removes it); only the recorder removes its own journal once that journal's session is
// complete. Frames that check out are recovered past damaged ones (the reader
// resynchronises on the next frame marker); the scans lost in a damaged stretch are
// marked as a gap. Scans missing between blocks (ring overflows) are stored as
// kGapFillCount with a "gap" event, so the uniform clock stays right. Timed samples of
// polled channels become explicit-time values (and their latencies the companion
// "<name>_latency" channel); the start frame's origin goes into the group "clock".
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

struct ConvertResult {
  std::filesystem::path journal;
  std::filesystem::path session;
  std::size_t channels = 0;
  std::uint64_t scans = 0;  // per channel, gaps included
  std::uint64_t gap_scans = 0;
  std::size_t events = 0;
  std::uint64_t journal_bytes = 0;
  std::uint64_t bytes_dropped = 0;  // after the last valid frame (a torn or damaged block)
  std::string drop_reason;          // why, "" when nothing was dropped
  bool ended_cleanly = false;       // the journal has its end mark
  bool already_complete = false;    // the session existed: only the journal was left
  double scan_rate_hz = 0.0;
  std::int64_t start_monotonic_ns = -1;  // from the journal's start frame; -1 when none
  std::int64_t start_realtime_ns = 0;    // UTC at that moment (ns since 1970); 0: unknown
  std::uint64_t timed_samples = 0;       // of the polled (explicit-time) channels
  std::uint64_t unordered_samples = 0;   // timed samples dropped: not after the one before
  // Damaged stretches between frames that check out, skipped: how many, their bytes, the
  // scans lost in them (marked as gaps, not in gap_scans) and the first one's reason.
  std::uint64_t damaged_stretches = 0;
  std::uint64_t damaged_bytes = 0;
  std::uint64_t damaged_scans = 0;
  std::string first_damage;
  std::string header_repair;           // what of the journal's header was repaired, "" none
  std::filesystem::path kept_journal;  // recovery: where the journal is kept
  std::string keep_problem;            // recovery: why it could not be renamed, "" when it was
  std::string brief_report() const;
};

struct ConvertOptions {
  SessionWriterOptions writer;
  // Events added after the journal's own (e.g. "recovered").
  std::function<std::vector<SessionEvent>(const ConvertResult& so_far)> closing_events;
  // Side groups written before closing (the simulated bench's truth).
  std::function<void(SessionWriter&)> extras;
  std::string validate() const { return writer.validate(); }
};

// Writes `session` from `journal` (via SESSION.partial and a rename); the journal is left
// as it is (the recorder removes its own; recovery renames it). The session must not
// exist. Throws JournalError / SessionError naming the file; on failure the partial file
// is removed.
ConvertResult convert_journal(const std::filesystem::path& journal,
                              const std::filesystem::path& session, const ConvertOptions& options);

struct RecoverOptions {
  std::filesystem::path out;  // empty: the journal's path without ".journal"
  SessionWriterOptions writer;
  std::string validate() const { return writer.validate(); }
};

// Recovers an unfinished session. `file` is the journal, or the session it belongs to
// (then "FILE.journal" is used). Refuses a journal that a running recording holds
// locked. The session gets an event of kind "recovered". If the session already exists
// (the recording was killed after the session was complete but before the journal was
// removed), it is checked against the journal. Afterwards, and when the journal holds
// nothing (the recording died while writing its header: JournalHeaderIncomplete, saying
// so), the journal is renamed "JOURNAL.recovered" ("JOURNAL.recovered-2", ... when that
// exists; never replacing a file) and kept_journal says where; a journal that cannot be
// recovered (refused) is left as it is under its own name.
ConvertResult recover_session(const std::filesystem::path& file,
                              const RecoverOptions& options = {});

// Journals in `folder` (files ending in ".journal" that start like a doorbench journal)
// that no running recording holds, i.e. unfinished sessions to recover.
std::vector<std::filesystem::path> find_unfinished_sessions(const std::filesystem::path& folder);

}  // namespace doorbench
