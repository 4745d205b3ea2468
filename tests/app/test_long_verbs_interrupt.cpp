// `fit`, `loop` and `spec` stopped by SIGINT or SIGTERM at several moments of their work: each
// ends within a second of the signal (the fits at their next solver iteration, the Monte Carlo
// at its next sample, the PDF renderer killed), with exit status 128 + the signal's number,
// and says what it kept: nothing before a whole result, else the result marked interrupted.
//
// The moments are keyed to the verbs' own stage lines on stderr (not to sleeps from the start),
// so that they fall in the same stage on a quiet machine and a loaded one. Each verb runs on a
// recording the test makes: the simulated bench's 40 s session (six strokes at 1 kHz) for fit
// and loop, and a door's simulated TO-BE strokes for spec.
#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/session/pdf_output.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/physical_model.h"
#include "fixtures/temp_dir.h"
#include "tests/support/doorbench_process.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchProcess;
using doorbench::testing::read_file;
using doorbench::testing::TempDir;
namespace fs = std::filesystem;

// A moment: after stderr shows `line`, wait `after_s`, then send the signal.
struct Moment {
  std::string line;
  double after_s = 0.0;
  // What the verb's last stderr line starts with after the stop.
  std::string says;
  // Whether it wrote a result marked interrupted (else nothing).
  bool kept = false;
  // The signal may land either before the first whole result or after it (a fit's first
  // optimum takes about as long as `after_s` on a quiet machine): either is right, as long as
  // the verb says which, and a result it says it kept is marked interrupted.
  bool either = false;
};

struct Stopped {
  int status = 0;
  double seconds = 0.0;  // from the signal to the exit
  std::string err;
};

Stopped stop_at(const std::vector<std::string>& args, const TempDir& dir, const Moment& moment,
                int signal_number, const std::string& tag) {
  DoorbenchProcess verb(args, (dir / ("stdout-" + tag + ".txt")).string());
  INFO(tag << ": waiting for '" << moment.line << "'");
  REQUIRE(verb.wait_for(moment.line, 900));
  std::this_thread::sleep_for(std::chrono::duration<double>(moment.after_s));
  const auto signalled = std::chrono::steady_clock::now();
  verb.send_signal(signal_number);
  Stopped stopped;
  stopped.status = verb.wait_exit(60);
  stopped.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  stopped.err = verb.err();
  return stopped;
}

std::string last_line(const std::string& text) {
  const std::size_t end = text.find_last_not_of('\n');
  if (end == std::string::npos) return "";
  const std::size_t begin = text.rfind('\n', end);
  return text.substr(begin == std::string::npos ? 0 : begin + 1, end - begin);
}

// Runs the verb once per moment, alternating SIGINT and SIGTERM, into OUT-k.
void check_moments(const std::string& verb, const std::vector<std::string>& args_before_out,
                   const TempDir& dir, const std::vector<Moment>& moments) {
  for (std::size_t k = 0; k < moments.size(); ++k) {
    const Moment& moment = moments[k];
    const int signal_number = k % 2 == 0 ? SIGINT : SIGTERM;
    const std::string name = signal_number == SIGINT ? "SIGINT" : "SIGTERM";
    const fs::path out = dir / (verb + "-" + std::to_string(k));
    std::vector<std::string> args = args_before_out;
    args.push_back("--out");
    args.push_back(out.string());
    const Stopped stopped = stop_at(args, dir, moment, signal_number, verb + std::to_string(k));
    INFO(verb << ", " << name << " " << moment.after_s << " s after '" << moment.line
              << "': " << stopped.err);
    CHECK(stopped.status == 128 + signal_number);
    CHECK(stopped.seconds <= 1.0);
    CHECK(last_line(stopped.err).rfind("doorbench: " + verb + ": " + name + " " + moment.says, 0) ==
          0);
    const std::string nothing = ": nothing was finished; nothing written to " + out.string() + "/";
    const bool said_nothing = last_line(stopped.err).ends_with(nothing);
    if (moment.either && !said_nothing) {
      CHECK_THAT(last_line(stopped.err), Catch::Contains(out.string() + "/"));
      CHECK(nlohmann::json::parse(read_file(out / "result.json")).contains("interrupted"));
    } else if (moment.either || !moment.kept) {
      CHECK_THAT(last_line(stopped.err), Catch::EndsWith(nothing));
      CHECK_FALSE(fs::exists(out / "result.json"));
    } else {
      CHECK_THAT(last_line(stopped.err), Catch::Contains(out.string() + "/"));
    }
  }
}

}  // namespace

TEST_CASE("fit, loop and spec: SIGINT or SIGTERM ends each within a second at several moments",
          "[slow][cli][signal]") {
  const TempDir dir("long_verbs_interrupt");
  const fs::path session = dir / "bench.h5";
  REQUIRE(doorbench::testing::run_doorbench_shell(
              "record --duration-s 40 --out '" + session.string() + "'", dir)
              .status == 0);

  SECTION("fit") {
    check_moments("fit", {"fit", session.string(), "--model", "sensory"}, dir,
                  {{"fitting the sensory model", 0.0, "stopped the fit during ", false},
                   {"fitting the sensory model", 0.8, "stopped the fit during ", false, true},
                   {"global search: 0 of", 0.1,
                    "stopped the fit during the global search: the fit is the data-derived "
                    "start's, without held-out metrics",
                    true}});
    // The fit stopped in its global stage is written, marked: the first start's fit.
    const nlohmann::json result = nlohmann::json::parse(read_file(dir / "fit-2" / "result.json"));
    CHECK(result.at("interrupted") ==
          "during the global search: the fit is the data-derived start's, without held-out "
          "metrics");
    CHECK(result.at("held_out").is_null());
    // report.md says so first.
    CHECK_THAT(read_file(dir / "fit-2" / "report.md"),
               Catch::Contains("\n## Result\n\n**SIGINT stopped the fit during the global search: "
                               "the fit is the data-derived start's, without held-out "
                               "metrics.**\n\nFit of the sensory model ("));
  }
  SECTION("loop") {
    check_moments("loop", {"loop", session.string(), "--model", "sensory"}, dir,
                  {{"fitting the start model", 0.5, "stopped the loop during ", false},
                   {"start model: ", 0.3, "stopped the loop: interrupted during step 1", true}});
    const nlohmann::json result = nlohmann::json::parse(read_file(dir / "loop-1" / "result.json"));
    CHECK(result.at("interrupted") == true);
  }
  SECTION("spec") {
    // The TO-BE door: the reference physical door with a softer latch (as test_spec_command).
    const doorbench::DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
    std::vector<double> values(asis.parameter_values().begin(), asis.parameter_values().end());
    values[doorbench::physical::kFl0] *= 0.7;
    const auto asis_file = dir.write("asis.json", doorbench::to_parameter_json(asis));
    const auto tobe_file =
        dir.write("tobe.json", doorbench::to_parameter_json(asis.with_parameter_values(values)));
    const fs::path tobe = dir / "tobe.csv";
    REQUIRE(doorbench::testing::run_doorbench_shell(
                "simulate --model physical --params '" + tobe_file.string() +
                    "' --hand open-close --duration-s 6 --out '" + tobe.string() + "'",
                dir)
                .status == 0);
    std::vector<Moment> moments = {
        {"inverse design: fitting", 0.3, "stopped the specification during ", false},
        {"tolerance Monte Carlo: 0 of", 0.2,
         "stopped the specification during the tolerance Monte Carlo: no tolerance analysis",
         true}};
    if (!doorbench::find_executable("weasyprint").empty()) {
      moments.push_back({"(spec.pdf: weasyprint renders", 0.3,
                         "stopped the specification during the PDF rendering: no spec.pdf", true});
    } else {
      WARN("weasyprint not installed: the PDF's moment is not tried");
    }
    check_moments("spec",
                  {"spec", tobe.string(), "--asis", asis_file.string(), "--samples", "2000"}, dir,
                  moments);
    const nlohmann::json spec = nlohmann::json::parse(read_file(dir / "spec-1" / "spec.json"));
    CHECK(spec.at("interrupted") == "during the tolerance Monte Carlo: no tolerance analysis");
    CHECK(spec.at("tolerances").is_null());
  }
}
