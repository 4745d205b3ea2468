// Fuzzes the recording journal's reader and recovery (acquisition/record/journal.h, recovery.h):
// any bytes on disk give frames up to the first bad one and a session, or a JournalError /
// SessionError naming the file; nothing else may escape, crash or be undefined. Each input
// is tried twice: as it is, and with its CRC-32s made right (the header's and each frame's,
// layout in docs/session-format.md), so that mutations reach the header's JSON and the
// frames' contents instead of stopping at a checksum. Each is written to a file of the
// process's own, read frame by frame, then recovered.
#include "acquisition/record/journal.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "acquisition/record/recovery.h"

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

std::uint32_t get32(const std::vector<std::uint8_t>& bytes, std::size_t at) {
  std::uint32_t value;
  std::memcpy(&value, bytes.data() + at, 4);
  return value;
}

void put32(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t value) {
  std::memcpy(bytes.data() + at, &value, 4);
}

// The same bytes with the header's and every whole frame's checksum recomputed.
std::vector<std::uint8_t> with_checksums(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  constexpr std::size_t kHead = 8 + 12;  // magic, version, JSON length, JSON CRC
  if (bytes.size() < kHead) return bytes;
  const std::uint32_t json_bytes = get32(bytes, 12);
  if (json_bytes > bytes.size() - kHead) return bytes;
  put32(bytes, 16, doorbench::crc32({bytes.data() + kHead, json_bytes}));
  std::size_t at = kHead + json_bytes;
  while (bytes.size() - at >= 16) {  // magic, type, payload length, CRC, payload
    const std::uint32_t payload = get32(bytes, at + 8);
    if (payload > bytes.size() - at - 16) break;
    std::uint32_t crc = doorbench::crc32({bytes.data() + at + 4, 8});
    crc = doorbench::crc32({bytes.data() + at + 16, payload}, crc);
    put32(bytes, at + 12, crc);
    at += 16 + payload;
  }
  return bytes;
}

void read_and_recover(const std::uint8_t* data, std::size_t size) {
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
  // The fuzzer's own scratch copies (recovery keeps a journal it recovered, renamed).
  std::filesystem::remove(journal, ignored);
  std::filesystem::remove(folder() / "s.h5.journal.recovered", ignored);
  std::filesystem::remove(session, ignored);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  read_and_recover(data, size);
  const std::vector<std::uint8_t> repaired = with_checksums(data, size);
  read_and_recover(repaired.data(), repaired.size());
  return 0;
}
