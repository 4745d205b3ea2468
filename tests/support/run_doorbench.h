#pragma once
// Runs the doorbench executable through the shell for tests of whole commands: stdout and
// stderr captured in files of `dir`, the exit status decoded. `environment` is put before
// the command (e.g. "DOORBENCH_COMEDI_LIBRARY=..."), `stdin_from` is a shell command whose
// output becomes doorbench's stdin (default: nothing, i.e. EOF at once).
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "fixtures/temp_dir.h"

namespace doorbench::testing {

struct DoorbenchRun {
  int status = -1;  // the exit status; -1 when it did not exit normally
  std::string out, err;
};

inline DoorbenchRun run_doorbench_shell(const std::string& args, const TempDir& dir,
                                        const std::string& environment = "",
                                        const std::string& stdin_from = "cat /dev/null") {
  const auto out = dir / "stdout.txt";
  const auto err = dir / "stderr.txt";
  const std::string command = std::string("(")
                                  .append(stdin_from)
                                  .append(") | ")
                                  .append(environment)
                                  .append(" '" DOORBENCH_EXECUTABLE "' ")
                                  .append(args)
                                  .append(" > '")
                                  .append(out.string())
                                  .append("' 2> '")
                                  .append(err.string())
                                  .append("'");
  DoorbenchRun run;
  const int status = std::system(command.c_str());
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream o(out), e(err);
  std::stringstream os, es;
  os << o.rdbuf();
  es << e.rdbuf();
  run.out = os.str();
  run.err = es.str();
  return run;
}

// The comedi device emulator in place of libcomedi, for run_doorbench_shell's environment.
inline std::string comedi_emulator_environment() {
  return "DOORBENCH_COMEDI_LIBRARY='" DOORBENCH_COMEDI_EMULATOR "'";
}

// `doorbench simulate` of the sensory reference door opened and closed by the virtual hand,
// duration_s at rate_hz, into the CSV `dir / name`; returns its path ("" when it failed).
inline std::string simulate_open_close_csv(const TempDir& dir, const std::string& name,
                                           double duration_s, double rate_hz) {
  const std::string csv = (dir / name).string();
  const DoorbenchRun run = run_doorbench_shell(
      "simulate --model sensory --hand open-close --duration-s " + std::to_string(duration_s) +
          " --rate-hz " + std::to_string(rate_hz) + " --out '" + csv + "'",
      dir);
  return run.status == 0 ? csv : "";
}

}  // namespace doorbench::testing
