#pragma once
// The design specification as one call (docs/design-spec.md): TO-BE recordings (or a
// panel's feel) and the AS-IS door in; the inverse design, the felt quantities before and
// after, the check, the tolerances (and the panel's, from a campaign) out, written as
// spec.json, spec.html (spec.pdf) and tobe-params.json into SpecOptions::out_dir.
// `doorbench spec` and the demo call it alike.
//
//   SpecOptions options;
//   options.tobe_paths = {"tobe.h5"};
//   options.asis_path = "fit-asis/";
//   options.out_dir = "spec";
//   if (std::string problem = options.validate(); !problem.empty()) ...;
//   const SpecSummary summary = specify(options);
//   std::cout << summary.brief_report();
//
// Errors: SpecOptionsError (a std::invalid_argument) for options that validate() refuses
// or that do not fit the AS-IS door (a --fixed or --costs name it lacks; the messages name
// the command line's options, as the verb shows them); StopRequested when stop_requested asks
// before the design is whole (nothing is written then); std::runtime_error naming the file
// for inputs that cannot be read, and when the output folder may not be written
// (docs/output-files.md).
// Thread safety: one call per thread; the Monte Carlo runs on its own pool and calls
// monte_carlo_progress from its threads.
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/design/inverse_design.h"
#include "analysis/design/panel_spec.h"
#include "analysis/design/spec_report.h"
#include "core/stop_request.h"

namespace doorbench {

class SpecOptionsError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct SpecOptions {
  std::vector<std::filesystem::path> tobe_paths;  // sessions or CSV recordings
  // A physical parameter file, or a `doorbench fit` folder holding fitted-params.json.
  std::filesystem::path asis_path;
  // A recording of the AS-IS door on the same bench as the TO-BE recordings: the AS-IS door
  // is first corrected to it by the sparse search (the bench's own effects then stay out of
  // the design). Empty: the AS-IS file as it is.
  std::filesystem::path asis_recording;
  std::filesystem::path out_dir;
  bool overwrite = false;  // write into an out_dir that exists and is not empty
  // Parameters kept at their AS-IS values; nullopt: the inverse design's default set.
  std::optional<std::vector<std::string>> fixed;
  std::map<std::string, double> costs;    // costs of change overriding the defaults
  std::filesystem::path tolerances_path;  // empty: the default tolerances
  int samples = 1000;                     // Monte Carlo samples, >= 2
  int threads = 0;                        // 0: every core
  unsigned long long seed = 1;
  double regularization = InverseDesignOptions{}.regularization;
  int starts = 3;
  bool motion_only = false;  // ignore the commanded torque of playback sessions
  bool pdf = true;           // render spec.pdf
  bool tolerances = true;    // run the tolerance analysis
  // A `campaign analyze` folder: the TO-BE feel from the panel when no TO-BE recordings are
  // given, the JNDs for the perceptual tolerance table. Empty: none. Its analysis.json is
  // read by `read_campaign` (study::read_campaign_for_spec: study/ is above this library),
  // after the output folder is checked.
  std::filesystem::path campaign_dir;
  std::function<CampaignForSpec(const std::filesystem::path& folder)> read_campaign;
  double felt_share = 0.05;  // with a campaign: 0 < share < 1
  std::string command;       // how the specification was asked for, for the report
  StopHook stop_requested;   // asked by the fits and the Monte Carlo
  // Progress for the operator, one line at a time without its newline; null: none.
  std::function<void(const std::string&)> progress;
  std::function<void(int done, int total)> monte_carlo_progress;  // null: none

  // "" when usable; else the first problem: "--samples must be >= 2", "--threads must be >=
  // 0", "spec: give TO-BE recordings or --campaign FOLDER", "--campaign needs the tolerance
  // analysis: drop --no-tolerances", "--felt-share must be between 0 and 1", "a campaign
  // needs its reader (read_campaign)".
  std::string validate() const;
};

struct SpecSummary {
  std::filesystem::path asis_file;  // the parameter file read
  InverseDesignResult design;
  SpecEvaluation evaluation;  // evaluation.interrupted: what a stop request cut
  SpecReportFiles files;
  std::filesystem::path params_file;  // OUT/tobe-params.json
  // A stop request during the PDF's rendering: spec.json, spec.html and tobe-params.json are
  // complete, spec.pdf is not there.
  bool pdf_interrupted = false;

  // The design, its check, the tolerances (and the panel's) and the files written.
  std::string brief_report() const;
};

// Runs the specification. Throws as the header says.
SpecSummary specify(const SpecOptions& options);

}  // namespace doorbench
