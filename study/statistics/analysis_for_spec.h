#pragma once
// `doorbench spec --campaign OUT`: a `campaign analyze` folder's analysis.json (written by
// analysis.h) read back into what the specification takes (analysis/design/panel_spec.h):
// the preference scale with each row's parameter file and the favourite chosen from it
// (choose_favourite), the panel's thresholds (participant "panel") and the felt
// quantities' JNDs chosen from them (assign_felt_jnds), and the tuned doors' centre.
//
// Errors: std::runtime_error naming analysis.json and the field (e.g.
// "OUT/analysis.json: jnd[1].weber_fraction: a positive number expected").
// Thread safety: a pure function of the file read.
#include <filesystem>

#include "analysis/design/panel_spec.h"

namespace doorbench::study {

// Reads FOLDER/analysis.json. Throws std::runtime_error for a missing or malformed file
// (naming the field); a missing jnd section is not an error (typical JNDs, said in notes).
CampaignForSpec read_campaign_for_spec(const std::filesystem::path& folder);

}  // namespace doorbench::study
