// Not a timing test: the poll rate ModbusSource achieves and its request→reply latency
// distribution against the loopback pymodbus server (tests/modbus/transmitter_server.py),
// for docs/PERFORMANCE.md. Runs 1 and 3 channels at 100 Hz and 1000 Hz each.
//   build/bench/doorbench_modbus_poll [seconds per run, default 20]
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "fixtures/modbus_test_server.h"
#include "sensors/modbus_source.h"

namespace {

std::string rig_text(int port, int channels, double rate_hz) {
  std::string text =
      "[bench]\nname = \"bench\"\n[daq]\nbackend = \"none\"\n[[modbus.devices]]\nname = "
      "\"server\"\ntransport = \"tcp\"\nhost = \"127.0.0.1\"\nport = " +
      std::to_string(port) + "\n";
  for (int c = 0; c < channels; ++c) {
    text +=
        "[[channels]]\nname = \"force" + std::to_string(c) +
        "\"\nsensor = \"load_cell\"\nserial = \"s\"\nbackend = \"modbus\"\nunit = \"N\"\n"
        "[channels.modbus]\ndevice = \"server\"\nunit_id = 1\nregister = \"input\"\naddress = " +
        std::to_string(2 * c) +
        "\ntype = \"float32\"\nbyte_order = \"big\"\nword_order = \"big\"\nrange = [-700, "
        "700]\npoll_rate_hz = " +
        std::to_string(rate_hz) + "\n";
  }
  return text;
}

double cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

void run(int channels, double rate_hz, double seconds) {
  doorbench::testing::TcpTransmitterServer server;
  const auto rig = doorbench::parse_rig(rig_text(server.port, channels, rate_hz), "bench", "");
  doorbench::sensors::ModbusSource source(rig);
  std::vector<std::vector<doorbench::PolledSample>> by_channel(static_cast<std::size_t>(channels));
  std::array<doorbench::PolledSample, 1024> buffer{};
  std::array<doorbench::PolledEvent, 64> events{};
  std::size_t event_count = 0;
  const double cpu_before = cpu_s();
  source.start();
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  auto drain = [&] {
    for (std::size_t n; (n = source.take_samples(buffer)) > 0;) {
      for (std::size_t i = 0; i < n; ++i) by_channel[buffer[i].channel].push_back(buffer[i]);
    }
    for (std::size_t n; (n = source.take_events(events)) > 0;) event_count += n;
  };
  while (std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    drain();
  }
  source.stop();
  drain();
  const double cpu = cpu_s() - cpu_before;
  const auto stats = source.statistics();

  std::vector<double> latency_ms;
  double min_rate = 1e300, max_rate = 0;
  for (const auto& samples : by_channel) {
    if (samples.size() < 2) {
      min_rate = 0;
      continue;
    }
    const double span_s =
        static_cast<double>(samples.back().request_ns - samples.front().request_ns) * 1e-9;
    const double rate = static_cast<double>(samples.size() - 1) / span_s;
    min_rate = std::min(min_rate, rate);
    max_rate = std::max(max_rate, rate);
    for (const auto& s : samples) latency_ms.push_back(static_cast<double>(s.latency_ns()) * 1e-6);
  }
  std::sort(latency_ms.begin(), latency_ms.end());
  auto pct = [&](double p) {
    if (latency_ms.empty()) return 0.0;
    return latency_ms[std::min(
        latency_ms.size() - 1,
        static_cast<std::size_t>(p * static_cast<double>(latency_ms.size())))];
  };
  std::printf(
      "| %d | %.0f | %.0f s | %.1f … %.1f | %llu | %.3f | %.3f | %.3f | %.3f | %llu | %zu | %.1f "
      "%% |\n",
      channels, rate_hz, seconds, min_rate, max_rate,
      static_cast<unsigned long long>(stats.samples), pct(0.5), pct(0.9), pct(0.99),
      latency_ms.empty() ? 0.0 : latency_ms.back(), static_cast<unsigned long long>(stats.faults),
      event_count, 100.0 * cpu / seconds);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 20.0;
  if (!(seconds > 0)) {
    std::fprintf(stderr, "usage: doorbench_modbus_poll [seconds per run > 0]\n");
    return 2;
  }
  std::printf(
      "| channels | requested Hz each | run | achieved Hz per channel (min … max) | samples | "
      "latency p50 ms | p90 ms | p99 ms | max ms | faults | events | doorbench CPU |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const double rate : {100.0, 1000.0}) {
    for (const int channels : {1, 3}) run(channels, rate, seconds);
  }
  return 0;
}
