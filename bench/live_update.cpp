// CPU time of the live view's work per displayed update (viewer/live_journal.h): a block of
// 10 ms of scans appended to the journal, poll() reading it, update_plots() rebuilding the
// plotted window of every channel. 8 channels at 50 kS/s (the recorder's largest tested
// rate) with a 10 s window: 500 k samples per channel plotted. Results: docs/PERFORMANCE.md.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <vector>

#include "acquisition/record/journal.h"
#include "fixtures/temp_dir.h"
#include "viewer/live_journal.h"

namespace {

using namespace doorbench;

void live_update(benchmark::State& state) {
  const std::size_t channels = 8;
  const double rate_hz = 50000.0;
  const std::size_t block = 500;  // 10 ms
  const testing::TempDir dir("live_bench");
  const auto path = dir / "live.h5.journal";
  JournalHeader header;
  ChannelInfo info;
  info.raw_scale = 1e-3;
  info.unit = std::string(1, 'V');
  info.sample_rate_hz = rate_hz;
  for (std::size_t c = 0; c < channels; ++c) {
    info.name = std::string("ch").append(std::to_string(c));
    header.channels.push_back(info);
  }
  header.scan_rate_hz = rate_hz;
  header.backend = "bench";
  viewer::LiveOptions options;
  options.window_s = static_cast<double>(state.range(0));
  options.capacity_samples = static_cast<std::size_t>(options.window_s * rate_hz) + block;
  {
    JournalWriter journal(path, header, block);
    journal.append_start(1, 2);
    std::vector<std::int32_t> counts(channels * block);
    std::uint64_t scan = 0;
    const auto append = [&] {
      for (std::size_t i = 0; i < counts.size(); ++i) {
        counts[i] = static_cast<std::int32_t>((scan + i % block) % 4096);
      }
      journal.append_scans(scan, block, counts.data(), block);
      scan += block;
    };
    // The window full before timing starts.
    viewer::LiveJournal live(path, options);
    std::vector<viewer::PlotView> plots;
    while (static_cast<double>(scan) < options.window_s * rate_hz) append();
    live.poll();
    live.update_plots(plots);
    for (auto _ : state) {
      state.PauseTiming();
      append();
      state.ResumeTiming();
      live.poll();
      live.update_plots(plots);
      benchmark::DoNotOptimize(plots.data());
    }
    state.counters["plotted_samples"] = static_cast<double>(plots[0].series[0]->size() * channels);
  }
}

}  // namespace

BENCHMARK(live_update)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);
