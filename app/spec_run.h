#pragma once
// `doorbench spec`'s options as typed, and the verb's run: they are parsed into SpecOptions
// and the specification is made by specify() (analysis/design/specify.h), which the demo
// calls too; the summary goes to stdout.
#include <string>
#include <vector>

#include "analysis/design/inverse_design.h"

namespace doorbench::app {

struct SpecCommandOptions {
  std::vector<std::string> tobe_paths;
  std::string asis_path;
  // A recording of the AS-IS door on the same bench as the TO-BE recordings: the AS-IS
  // door is first corrected to it by the sparse search (the bench's own effects then stay
  // out of the design). Empty: the AS-IS file as it is.
  std::string asis_recording;
  std::string out_dir;
  std::string fixed;  // empty: the inverse design's default fixed set
  bool fixed_given = false;
  // Costs of change overriding the defaults, "F0=1,k_s=5" (docs/inverse-design.md).
  std::string costs;
  std::string tolerances_path;
  int samples = 1000;
  int threads = 0;
  unsigned long long seed = 1;
  double regularization = InverseDesignOptions{}.regularization;
  int starts = 3;
  bool motion_only = false;  // ignore the commanded torque of playback sessions
  bool no_pdf = false;
  bool no_tolerances = false;
  // A `doorbench campaign analyze` folder (analysis.json): the TO-BE feel from the panel
  // when no TO-BE recordings are given, the JNDs for the perceptual tolerance table
  // (docs/design-spec.md, "The specification from the panel"). Empty: none.
  std::string campaign_dir;
  // --felt-share as typed ("5%" or "0.05"); empty: 5 %. Only with a campaign.
  std::string felt_share;
  bool show_progress = true;  // progress lines on stderr
  // Write into an --out folder that exists and is not empty (docs/output-files.md); the
  // demo, which owns its folder, sets it.
  bool overwrite = false;
};

// Throws UsageError for bad options (also those specify() refuses), Interrupted when a signal
// stopped it, std::runtime_error for files and failures.
void run_spec(const SpecCommandOptions& options);

}  // namespace doorbench::app
