#pragma once
// What the specification takes from a panel (docs/design-spec.md, "The specification from
// the panel"): the preference scale, the panel's thresholds, each felt quantity's JND
// (measured, or typical and said so) and the TO-BE feel (the favourite variant's parameter
// file, or the centre of the panel's tuned doors). study/ reads these from a campaign's
// analysis.json (study/statistics/analysis_for_spec.h); the rules choosing the JNDs and the
// TO-BE door are here, with the specification.
//
// Errors: std::runtime_error naming analysis.json (see campaign_tobe_model).
// Thread safety: pure functions of their arguments and the files they read.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "analysis/design/perceptual_tolerance.h"
#include "analysis/model/door_model.h"

namespace doorbench {

struct CampaignForSpec {
  std::filesystem::path analysis_path;                         // FOLDER/analysis.json
  std::vector<PanelPreference> preference;                     // as in the file
  std::map<std::string, std::filesystem::path> variant_files;  // preference rows' files, by variant
  std::vector<PanelThreshold> thresholds;      // the panel's rows (participant "panel")
  std::vector<FeltJnd> jnds;                   // one per felt quantity, measured or typical
  std::vector<std::string> notes;              // what was assumed, for the report and stderr
  std::string favourite;                       // the variant of largest worth ("" without a scale)
  std::filesystem::path favourite_file;        // its parameter file, when the row names one
  std::map<std::string, double> tuned_centre;  // tuning.parameters[].centre (non-null)
  int tuned_doors = 0;                         // tuning.doors' count
};

// Sets campaign.jnds, one per felt quantity (felt_jnd_kinds' order): the first of
// `campaign.thresholds` measuring a parameter that stands for the quantity, else its typical
// JND. A threshold that stands for no quantity gets a note ("the panel's JND of J_d stands
// for no felt quantity of the specification: not used").
void assign_felt_jnds(CampaignForSpec& campaign);

// Sets campaign.favourite and favourite_file: the variant of `campaign.preference` with the
// largest worth (the first of equals) and its file in variant_files (empty when it has
// none), or none ("") without a preference scale.
void choose_favourite(CampaignForSpec& campaign);

// The TO-BE door the panel chose: the favourite variant's parameter file (its physical
// section, else its sensory one) when the campaign names it, else the AS-IS door with the
// tuned centre's physical parameters ("physical.NAME", or NAME when not a sensory
// parameter), else the reference sensory door with the tuned centre's sensory parameters.
// `source` says which and why. Throws std::runtime_error when the campaign gives neither.
DoorModel campaign_tobe_model(const CampaignForSpec& campaign, const DoorModel& asis,
                              std::string& source);

}  // namespace doorbench
