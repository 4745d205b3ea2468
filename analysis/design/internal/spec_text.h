#pragma once
// Wording that spec.json (spec_json.cpp) and spec.html (spec_report.cpp) share.
#include <string>

namespace doorbench::design_detail {

// The perceptual tolerance's criterion (perceptual_tolerance.h) in one sentence.
std::string felt_criterion_text();

}  // namespace doorbench::design_detail
