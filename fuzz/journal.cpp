// Fuzzes the recording journal's reader and recovery (acquisition/journal.h, recovery.h):
// any bytes on disk give frames up to the first bad one and a session, or a JournalError /
// SessionError naming the file; nothing else may escape, crash or be undefined. Each input
// is written to a file of its own process's, read frame by frame, then recovered.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "acquisition/journal.h"
#include "acquisition/recovery.h"

namespace {

// The process's scratch folder, removed when the fuzzer exits.
struct Scratch {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("doorbench-fuzz-journal-" + std::to_string(::getpid()));
  Scratch() { std::filesystem::create_directories(path); }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

const std::filesystem::path& folder() {
  static const Scratch scratch;
  return scratch.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path journal = folder() / "s.h5.journal";
  const std::filesystem::path session = folder() / "s.h5";
  std::error_code ignored;
  std::filesystem::remove(session, ignored);
  {
    std::ofstream out(journal, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    doorbench::JournalReader reader(journal);
    doorbench::JournalFrame frame;
    while (reader.next(frame)) {
    }
  } catch (const doorbench::JournalError&) {
  }
  try {
    doorbench::recover_session(journal);
  } catch (const doorbench::JournalError&) {
  } catch (const doorbench::SessionError&) {
  }
  std::filesystem::remove(journal, ignored);
  std::filesystem::remove(session, ignored);
  return 0;
}
