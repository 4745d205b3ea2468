// Not a timing: records a long session the way the recorder does (8 int32 channels at
// 10 kS/s, appended in blocks of 1000 scans) and prints the peak resident memory
// (VmHWM from /proc/self/status) before and after, to show that memory stays bounded
// whatever the recording's length (target: < 64 MB). For docs/PERFORMANCE.md.
//
//   doorbench_session_memory [SECONDS [FOLDER]]   (default: 3600 s in the temp folder)
//
// One hour is 288 M samples, 1.15 GB on disk; the file is deleted afterwards.
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"

namespace {

// A line of /proc/self/status in kB, e.g. "VmHWM", or -1.
long status_kb(const std::string& key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(key + ":", 0) == 0)
      return std::strtol(line.c_str() + key.size() + 1, nullptr, 10);
  }
  return -1;
}

void print_memory(const char* when) {
  std::printf("%-26s VmHWM %6.1f MB  VmRSS %6.1f MB (anon %6.1f, file %5.1f)\n", when,
              status_kb("VmHWM") / 1024.0, status_kb("VmRSS") / 1024.0,
              status_kb("RssAnon") / 1024.0, status_kb("RssFile") / 1024.0);
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const double seconds = argc > 1 ? std::atof(argv[1]) : 3600.0;
  const fs::path folder = argc > 2 ? fs::path(argv[2]) : fs::temp_directory_path();
  if (!(seconds > 0)) {
    std::fprintf(stderr, "usage: doorbench_session_memory [SECONDS [FOLDER]]\n");
    return 2;
  }
  constexpr int kChannels = 8;
  constexpr double kRateHz = 10000.0;
  constexpr std::size_t kBlock = 1000;
  const auto total_scans = static_cast<std::size_t>(seconds * kRateHz);
  const fs::path path = folder / ("doorbench_session_memory_" + std::to_string(::getpid()) + ".h5");

  std::vector<std::vector<std::int32_t>> blocks(kChannels, std::vector<std::int32_t>(kBlock));
  print_memory("start");
  const auto started = std::chrono::steady_clock::now();
  try {
    doorbench::SessionMetadata metadata;
    metadata.rig_name = "memory test";
    doorbench::SessionWriter writer(path, metadata);
    std::vector<int> channels;
    for (int c = 0; c < kChannels; ++c) {
      doorbench::ChannelInfo info;
      info.name = "ch" + std::to_string(c);
      info.sample_rate_hz = kRateHz;
      channels.push_back(writer.add_channel(info));
    }
    print_memory("session open, 8 channels");
    std::size_t scans = 0;
    while (scans < total_scans) {
      const std::size_t n = std::min(kBlock, total_scans - scans);
      for (int c = 0; c < kChannels; ++c) {
        for (std::size_t i = 0; i < n; ++i) {
          blocks[c][i] = static_cast<std::int32_t>((scans + i) * (c + 1) % 65536) - 32768;
        }
        writer.append_counts(channels[c], std::span<const std::int32_t>(blocks[c].data(), n));
      }
      scans += n;
      if (scans % (static_cast<std::size_t>(kRateHz) * 600) == 0) {
        print_memory(
            ("after " + std::to_string(scans / static_cast<std::size_t>(kRateHz)) + " s").c_str());
      }
    }
    writer.close();
  } catch (const std::exception& error) {
    std::fprintf(stderr, "doorbench_session_memory: %s\n", error.what());
    std::error_code ignored;
    fs::remove(path, ignored);
    return 1;
  }
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const auto bytes = fs::file_size(path);
  print_memory("closed");
  std::printf(
      "recorded %.0f s: %zu scans x %d channels = %.0f M samples, file %.1f MB "
      "(%.2f bytes/sample), %.1f s wall (%.0f MB/s)\n",
      seconds, total_scans, kChannels, total_scans * kChannels / 1e6, bytes / 1e6,
      static_cast<double>(bytes) / (static_cast<double>(total_scans) * kChannels), elapsed,
      bytes / 1e6 / elapsed);
  fs::remove(path);
  return 0;
}
