// Not a Google Benchmark: a sustained real-time run. Records a session from the emulated
// comedi card (tests/comedi_emulator, loaded in place of libcomedi) through the comedi
// backend and the recorder, every channel a counter signal, then reads the session back
// and checks every sample: none lost, none repeated, no overrun. Prints the CPU time the
// process used (getrusage) against the wall time. For docs/PERFORMANCE.md.
//
//   doorbench_comedi_throughput EMULATOR.so [SECONDS [CHANNELS [RATE_HZ [BUFFER_BYTES]]]]
//
// Defaults: 60 s, 8 channels, 50 kHz per channel, a 1 MiB kernel buffer.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "acquisition/record/recorder.h"
#include "acquisition/rig/rig_file.h"
#include "fixtures/temp_dir.h"
#include "sensors/comedi_backend.h"

namespace {

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_utime.tv_usec * 1e-6 + usage.ru_stime.tv_sec +
         usage.ru_stime.tv_usec * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s EMULATOR.so [SECONDS [CHANNELS [RATE_HZ [BUFFER_BYTES]]]]\n",
                 argv[0]);
    return 2;
  }
  const std::string emulator = argv[1];
  const double seconds = argc > 2 ? std::atof(argv[2]) : 60.0;
  const int channels = argc > 3 ? std::atoi(argv[3]) : 8;
  const double rate_hz = argc > 4 ? std::atof(argv[4]) : 50000.0;
  const long buffer_bytes = argc > 5 ? std::atol(argv[5]) : 1 << 20;

  namespace fs = std::filesystem;
  const doorbench::testing::TempDir scratch("comedi_throughput");
  const fs::path& dir = scratch.path;
  // A PCIe-6251-like board: 1 MS/s aggregate, 20 MHz timebase; counters on every channel.
  {
    std::ofstream device(dir / "comedi0");
    device << "board = pcie-6251\nbase_clock_ns = 50\nmin_convert_ns = 1000\n"
           << "buffer_bytes = " << buffer_bytes << "\ntransfer_bytes = 4096\n";
    for (int c = 0; c < channels; ++c) device << "signal." << c << " = counter\n";
  }
  std::ostringstream rig;
  rig << "[bench]\nname = \"throughput\"\n[clock]\nsample_rate_hz = " << rate_hz
      << "\nconvert_interval_s = 1e-6\n[daq]\nbackend = \"comedi\"\ndevice = \""
      << (dir / "comedi0").string() << "\"\n";
  for (int c = 0; c < channels; ++c) {
    rig << "[[channels]]\nname = \"ai" << c << "\"\nsensor = \"gyroscope\"\nserial = \"G" << c
        << "\"\nbackend = \"comedi\"\naddress = \"0/" << c
        << "\"\ncalibration = \"nominal\"\nunit = \"rad/s\"\n";
  }
  const doorbench::RigDefinition definition = doorbench::parse_rig(rig.str(), "throughput", dir);

  const auto& api = doorbench::sensors::load_comedi_library(emulator);
  doorbench::sensors::ComediOptions options;
  options.duration_s = seconds;
  doorbench::sensors::ComediBackend backend(definition, api, options);
  std::fprintf(stderr, "%s", backend.setup().brief_report().c_str());

  doorbench::SessionMetadata metadata;
  metadata.rig_name = "throughput";
  doorbench::RecordOptions record;
  // The recorder stops at this duration (NI boards count at most 2^24 scans, so a long run
  // acquires with stop TRIG_NONE; a short one ends by EOF at the same count).
  record.duration_s = seconds;
  record.block_scans = static_cast<std::size_t>(backend.scan_rate_hz() / 50);  // 20 ms
  const fs::path session_path = dir / "session.h5";
  const double cpu_before = cpu_seconds();
  const auto wall_before = std::chrono::steady_clock::now();
  const doorbench::RecordSummary summary =
      doorbench::record_session(backend, metadata, session_path, record);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_before).count();
  const double cpu_s = cpu_seconds() - cpu_before;

  // Every sample back from the file: counter = 1 + (scan + 7 channel) mod (maxdata − 1).
  const doorbench::SessionReader session(session_path);
  std::size_t checked = 0, wrong = 0;
  for (int c = 0; c < channels; ++c) {
    const std::string name = "ai" + std::to_string(c);
    const std::size_t count = session.sample_count(name);
    const double step_s = 10.0;
    for (double start = 0; start * backend.scan_rate_hz() < count; start += step_s) {
      const doorbench::ChannelSlice slice =
          session.read(name, start - 0.5 / backend.scan_rate_hz(),
                       start + step_s - 0.5 / backend.scan_rate_hz());
      for (std::size_t i = 0; i < slice.raw.size(); ++i) {
        const std::size_t scan = slice.first_index + i;
        const double expected = 1.0 + static_cast<double>((scan + 7 * c) % 65534);
        wrong += slice.raw[i] != expected;
        ++checked;
      }
    }
  }
  const auto expected_scans =
      static_cast<std::size_t>(std::llround(seconds * backend.scan_rate_hz()));
  const std::size_t expected_samples = expected_scans * channels;
  const std::uintmax_t file_bytes = fs::file_size(session_path);
  std::printf(
      "comedi throughput: %d channels x %.0f Hz (achieved %.3f Hz) for %.1f s\n"
      "  scans %zu of %zu, samples checked %zu of %zu, wrong %zu, overrun %s, end: %s\n"
      "  wall %.2f s, CPU %.2f s (%.1f %% of one core), session %.1f MB\n",
      channels, rate_hz, backend.scan_rate_hz(), seconds, summary.scans, expected_scans, checked,
      expected_samples, wrong, backend.overran() ? "YES" : "no", backend.end_reason().c_str(),
      wall_s, cpu_s, 100.0 * cpu_s / wall_s, file_bytes / 1e6);
  const bool ok = !backend.overran() && wrong == 0 && checked == expected_samples &&
                  summary.scans == expected_scans;
  return ok ? 0 : 1;
}
