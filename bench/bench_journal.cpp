// The recording journal at 8 channels × 50 kS/s (docs/crash-safety.md, PERFORMANCE.md):
//
// - journal_append: append blocks of 10 ms (500 scans × 8 int32 channels, 16 kB) with no
//   sync: what the writer thread costs per block. Counters: MB_s, realtime_x (seconds of
//   data written per second).
// - journal_flush: one flush interval's worth of blocks (argument: ms, 10 ms per block)
//   appended, then fdatasync; the time per iteration is the flush cost plus its writes.
//   Counters: sync_ms (the fdatasync alone, mean), realtime_x.
// - record_8x50k: the whole recorder, an unpaced synthetic 8 × 50 kS/s source, 2 s of
//   data: reading thread, ring, journal (synced every 50 ms), conversion to HDF5.
//   Counters: realtime_x, convert_share (fraction of the time after the last scan).
// Files go to the temp folder (the same disk as the build here) and are deleted.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/record/recorder.h"
#include "fixtures/temp_dir.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kChannels = 8;
constexpr double kRateHz = 50000.0;
constexpr std::size_t kBlockScans = 500;  // 10 ms

doorbench::JournalHeader bench_header() {
  doorbench::JournalHeader header;
  for (std::size_t c = 0; c < kChannels; ++c) {
    doorbench::ChannelInfo channel;
    channel.name = std::string("ai").append(std::to_string(c));
    channel.sample_rate_hz = kRateHz;
    header.channels.push_back(channel);
  }
  header.scan_rate_hz = kRateHz;
  return header;
}

std::vector<std::int32_t> block_counts() {
  std::vector<std::int32_t> counts(kChannels * kBlockScans);
  for (std::size_t i = 0; i < counts.size(); ++i) counts[i] = static_cast<std::int32_t>(i % 65536);
  return counts;
}

void journal_append(benchmark::State& state) {
  const doorbench::testing::TempDir scratch("bench_journal");
  const fs::path& folder = scratch.path;
  const std::vector<std::int32_t> counts = block_counts();
  std::uint64_t blocks = 0;
  {
    doorbench::JournalWriter journal(folder / "j.journal", bench_header(), kBlockScans);
    for (auto _ : state) {
      journal.append_scans(blocks * kBlockScans, kBlockScans, counts.data(), kBlockScans);
      ++blocks;
    }
  }
  const double bytes = double(blocks) * counts.size() * sizeof(std::int32_t);
  state.counters["MB_s"] = benchmark::Counter(bytes / 1e6, benchmark::Counter::kIsRate);
  state.counters["realtime_x"] =
      benchmark::Counter(double(blocks) * kBlockScans / kRateHz, benchmark::Counter::kIsRate);
}
// 20000 blocks: 200 s of data, a 320 MB file.
BENCHMARK(journal_append)->Unit(benchmark::kMicrosecond)->Iterations(20000)->UseRealTime();

void journal_flush(benchmark::State& state) {
  const doorbench::testing::TempDir scratch("bench_journal_flush");
  const fs::path& folder = scratch.path;
  const std::vector<std::int32_t> counts = block_counts();
  const auto blocks_per_flush = static_cast<std::size_t>(state.range(0) / 10);
  std::uint64_t blocks = 0;
  double sync_s = 0.0;
  std::uint64_t syncs = 0;
  {
    doorbench::JournalWriter journal(folder / "j.journal", bench_header(), kBlockScans);
    for (auto _ : state) {
      for (std::size_t b = 0; b < blocks_per_flush; ++b) {
        journal.append_scans(blocks * kBlockScans, kBlockScans, counts.data(), kBlockScans);
        ++blocks;
      }
      const auto start = Clock::now();
      journal.sync();
      sync_s += std::chrono::duration<double>(Clock::now() - start).count();
      ++syncs;
    }
  }
  state.counters["sync_ms"] = 1000.0 * sync_s / double(syncs);
  state.counters["realtime_x"] =
      benchmark::Counter(double(blocks) * kBlockScans / kRateHz, benchmark::Counter::kIsRate);
}
BENCHMARK(journal_flush)->Arg(10)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime();

// Synthetic counts as fast as asked: the recorder's own cost, not a sensor model's.
class SyntheticSource final : public doorbench::AcquisitionBackend {
 public:
  std::string description() const override { return "synthetic 8 x 50 kS/s"; }
  std::vector<doorbench::ChannelInfo> channels() const override { return bench_header().channels; }
  std::vector<doorbench::CalibrationRecord> calibrations() const override { return {}; }
  double scan_rate_hz() const override { return kRateHz; }
  void start() override { next_ = 0; }
  std::size_t read(doorbench::ScanBlock& block) override {
    const std::size_t n = block.capacity();
    for (std::size_t c = 0; c < kChannels; ++c) {
      for (std::size_t s = 0; s < n; ++s) {
        block.counts[c][s] = static_cast<std::int32_t>((next_ + s + c) % 65536);
      }
    }
    next_ += n;
    block.scan_count = n;
    last_read_ = Clock::now();
    return n;
  }
  void stop() override {}
  Clock::time_point last_read_;

 private:
  std::uint64_t next_ = 0;
};

void record_8x50k(benchmark::State& state) {
  const doorbench::testing::TempDir scratch("bench_record");
  const fs::path& folder = scratch.path;
  constexpr double kSeconds = 2.0;
  double total_s = 0.0, convert_s = 0.0;
  int run = 0;
  for (auto _ : state) {
    SyntheticSource source;
    doorbench::RecordOptions options;
    options.duration_s = kSeconds;
    const fs::path session = folder / std::string("s").append(std::to_string(run++)).append(".h5");
    const auto start = Clock::now();
    doorbench::record_session(source, doorbench::SessionMetadata{}, session, options);
    const auto end = Clock::now();
    total_s += std::chrono::duration<double>(end - start).count();
    convert_s += std::chrono::duration<double>(end - source.last_read_).count();
    fs::remove(session);
  }
  state.counters["realtime_x"] = kSeconds * run / total_s;
  state.counters["convert_share"] = convert_s / total_s;
}
BENCHMARK(record_8x50k)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace
