#pragma once
// The guided procedure on a live bench: for each reference it prompts the operator
// ("put 5 kg on the load cell, then press Enter"), waits for Enter, then reads windows
// of the signal until one is stable and keeps its mean and standard deviation as the
// point. Input and output are streams, so a test drives it through its prompts.
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "calibration/static_source.h"

namespace doorbench::calibration {

struct GuidedPoint {
  double reference = 0.0;   // in the record's unit (N, rad)
  std::string label;        // how the reference is named to the operator: "5 kg", "+4°"
  std::string instruction;  // what to do: "put 5 kg on the load cell"
  std::string branch;       // loading | unloading | ""
};

struct GuidedOptions {
  double window_s = 1.0;  // each point is the mean over one stable window of this length
  int max_windows = 5;    // windows read before the point is declared unstable
  // A window is stable when its standard deviation is at most max_std_V and the means of
  // its two halves differ by at most max_drift_V (a load still swinging, a tilt table
  // still settling, a creeping reading).
  double max_std_V = 0.0;
  double max_drift_V = 0.0;
  // For showing readings to the operator in physical units: value ≈ signal · this.
  double display_per_V = 1.0;
  std::string display_unit = "V";

  std::string validate() const;  // "" when usable
};

// Runs the points in order. Answers: an empty line (Enter) acquires, "q" aborts. Throws
// CalibrationError when the operator aborts, the input ends, or a point does not settle
// within max_windows (the message gives the last window's figures and the limits).
std::vector<CalibrationPoint> run_guided_points(StaticSignalSource& source,
                                                std::span<const GuidedPoint> points,
                                                const GuidedOptions& options, std::istream& in,
                                                std::ostream& out);

}  // namespace doorbench::calibration
