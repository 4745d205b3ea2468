// doorbench recover: the session of a recording that was killed, from its journal.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "acquisition/session/output_file.h"
#include "acquisition/session/printable.h"
#include "acquisition/record/recorder.h"
#include "acquisition/record/recovery.h"
#include "acquisition/rig/rig_file.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/tdms.h"
#include "app/commands.h"
#include "app/limit_watcher.h"
#include "app/session_recording.h"
#include "calibration/range_warnings.h"
#include "sensors/comedi_backend.h"
#include "sensors/modbus_source.h"
#include "simulated_bench/simulated_bench.h"

namespace doorbench::app {
namespace {

struct RecoverCommandOptions {
  std::string file;
  std::string out_path;
};

void run_recover(const RecoverCommandOptions& options) {
  RecoverOptions recover;
  recover.out = options.out_path;
  const ConvertResult result = recover_session(options.file, recover);
  std::cerr << "recovered " << result.brief_report() << "\n";
}

}  // namespace

void add_recover_command(CLI::App& app, Action& action) {
  auto recover = std::make_shared<RecoverCommandOptions>();
  CLI::App* recover_command = app.add_subcommand(
      "recover",
      "Make the session of a recording that was killed, lost power or ran out of disk from "
      "its journal (S.h5.journal); `record` does this by itself for its output folder");
  recover_command
      ->add_option("FILE", recover->file, "The journal (S.h5.journal), or the session S.h5")
      ->required();
  recover_command->add_option("--out", recover->out_path,
                              "The session to write; default: the journal's name without "
                              ".journal");
  recover_command->callback([recover, &action] { action = [recover] { run_recover(*recover); }; });
}

}  // namespace doorbench::app
