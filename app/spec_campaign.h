#pragma once
// `doorbench spec --felt-share`. What spec takes from a campaign is read by study/
// (study/statistics/analysis_for_spec.h) and chosen by analysis/design/panel_spec.h.
#include <string_view>

namespace doorbench::app {

// --felt-share: "5%" (percent) or "0.05" (a fraction); 0 < share < 1. Throws UsageError
// ("--felt-share: '150%' is not a share between 0 and 1 (e.g. 5% or 0.05)").
double parse_felt_share(std::string_view text);

}  // namespace doorbench::app
