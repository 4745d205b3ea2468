// Session write throughput against plain fwrite of the same bytes (target: ≥ 0.7× fwrite).
// Both write 8 int32 channels in blocks of 1000 samples per channel, 64 MB in all, to a
// file in the temp folder that is deleted afterwards; neither calls fsync, so both
// measure writing into the page cache. Each iteration runs fwrite, then the session
// writer; the reported time is the session's (manual time). Counters: session_MB_s,
// fwrite_MB_s and ratio (session / fwrite throughput). The argument is chunk_samples.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "core/clock.h"
#include "fixtures/temp_dir.h"

namespace {

namespace fs = std::filesystem;
using doorbench::seconds_since;
using doorbench::StageClock;

constexpr int kChannels = 8;
constexpr std::size_t kBlock = 1000;
constexpr std::size_t kTotalBytes = 64u << 20;
constexpr std::size_t kBlocksPerChannel = kTotalBytes / (kChannels * kBlock * sizeof(std::int32_t));
constexpr double kBytes = double(kBlocksPerChannel) * kChannels * kBlock * sizeof(std::int32_t);

void session_vs_fwrite(benchmark::State& state) {
  const doorbench::testing::TempDir scratch("bench_session");
  const fs::path& folder = scratch.path;
  const fs::path plain = folder / "plain.bin";
  const fs::path session = folder / "session.h5";

  std::vector<std::vector<std::int32_t>> blocks(kChannels, std::vector<std::int32_t>(kBlock));
  for (int c = 0; c < kChannels; ++c) {
    for (std::size_t i = 0; i < kBlock; ++i) {
      blocks[c][i] = static_cast<std::int32_t>(i * 2654435761u % 65536) - 32768 + c;
    }
  }
  doorbench::SessionWriterOptions options;
  options.chunk_samples = static_cast<std::size_t>(state.range(0));

  double fwrite_s = 0.0, session_s = 0.0;
  for (auto _ : state) {
    StageClock::time_point start = StageClock::now();
    std::FILE* file = std::fopen(plain.c_str(), "wb");
    if (!file) {
      state.SkipWithError("cannot create the fwrite file");
      break;
    }
    for (std::size_t b = 0; b < kBlocksPerChannel; ++b) {
      for (int c = 0; c < kChannels; ++c) {
        std::fwrite(blocks[c].data(), sizeof(std::int32_t), kBlock, file);
      }
    }
    std::fclose(file);
    fwrite_s += seconds_since(start);
    fs::remove(plain);

    start = StageClock::now();
    {
      doorbench::SessionWriter writer(session, doorbench::SessionMetadata{}, options);
      int channels[kChannels];
      for (int c = 0; c < kChannels; ++c) {
        doorbench::ChannelInfo info;
        info.name = "ch" + std::to_string(c);
        info.sample_rate_hz = 10000.0;
        channels[c] = writer.add_channel(info);
      }
      for (std::size_t b = 0; b < kBlocksPerChannel; ++b) {
        for (int c = 0; c < kChannels; ++c) writer.append_counts(channels[c], blocks[c]);
      }
      writer.close();
    }
    const double elapsed = seconds_since(start);
    session_s += elapsed;
    state.SetIterationTime(elapsed);
    fs::remove(session);
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["session_MB_s"] = kBytes * n / session_s / 1e6;
  state.counters["fwrite_MB_s"] = kBytes * n / fwrite_s / 1e6;
  state.counters["ratio"] = fwrite_s / session_s;
  state.SetBytesProcessed(static_cast<std::int64_t>(kBytes * n));
}

BENCHMARK(session_vs_fwrite)
    ->Arg(4096)
    ->Arg(16384)
    ->Arg(65536)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
