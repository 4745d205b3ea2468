#pragma once
// `doorbench spec --campaign OUT`: what the specification takes from a `campaign analyze`
// folder's analysis.json (docs/design-spec.md, "The specification from the panel") — the
// preference scale, the panel's thresholds, each felt quantity's JND (measured, or typical
// and said so) and the TO-BE feel (the favourite variant's parameter file, or the centre of
// the panel's tuned doors).
//
// Errors: std::runtime_error naming analysis.json and the field (e.g.
// "OUT/analysis.json: jnd[1].weber_fraction: a positive number expected").
// Thread safety: pure functions of the files read.
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/design/perceptual_tolerance.h"
#include "analysis/model/door_model.h"

namespace doorbench::app {

struct CampaignForSpec {
  std::filesystem::path analysis_path;         // FOLDER/analysis.json
  std::vector<PanelPreference> preference;     // as in the file
  std::vector<PanelThreshold> thresholds;      // the panel's rows (participant "panel")
  std::vector<FeltJnd> jnds;                   // one per felt quantity, measured or typical
  std::vector<std::string> notes;              // what was assumed, for the report and stderr
  std::string favourite;                       // the variant of largest worth ("" without a scale)
  std::filesystem::path favourite_file;        // its parameter file, when the row names one
  std::map<std::string, double> tuned_centre;  // tuning.parameters[].centre (non-null)
  int tuned_doors = 0;                         // tuning.doors' count
};

// Reads FOLDER/analysis.json. Throws std::runtime_error for a missing or malformed file
// (naming the field); a missing jnd section is not an error (typical JNDs, said in notes).
CampaignForSpec read_campaign_for_spec(const std::filesystem::path& folder);

// The TO-BE door the panel chose: the favourite variant's parameter file (its physical
// section, else its sensory one) when the campaign names it, else the AS-IS door with the
// tuned centre's physical parameters ("physical.NAME", or NAME when not a sensory
// parameter), else the reference sensory door with the tuned centre's sensory parameters.
// `source` says which and why. Throws std::runtime_error when the campaign gives neither.
DoorModel campaign_tobe_model(const CampaignForSpec& campaign, const DoorModel& asis,
                              std::string& source);

// --felt-share: "5%" (percent) or "0.05" (a fraction); 0 < share < 1. Throws UsageError
// ("--felt-share: '150%' is not a share between 0 and 1 (e.g. 5% or 0.05)").
double parse_felt_share(std::string_view text);

}  // namespace doorbench::app
