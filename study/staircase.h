#pragma once
// The adaptive staircase of a jnd block (docs/campaign.md): Levitt's transformed up-down
// rule (H. Levitt, "Transformed up-down methods in psychoacoustics", J. Acoust. Soc. Am. 49,
// 1971) on the increment Δ = level − 1 of the comparison over the standard. After `down`
// correct answers in a row Δ is divided by step_factor, after each wrong answer multiplied
// by it; the level is kept within [min_level, max_level]. The track converges on the level
// answered correctly with probability 0.5^(1/down): 70.7 % for 2-down-1-up, 79.4 % for
// 3-down-1-up.
//
// The levels are not in the plan: each is decided at run time from the answers before it,
// deterministically, so a resumed run (which reads those answers back from trials.csv)
// continues the same track.
// Thread safety: free functions.
#include <vector>

#include "study/campaign_file.h"

namespace doorbench::study {

// The level of the next trial after `correct` (true: the comparison was named stronger).
double staircase_level(const Block& block, const std::vector<bool>& correct);

// The threshold estimate: the geometric mean of the levels' increments at the last reversals
// (up to 6; the first 2 reversals left out when there are more than 4), as a level 1 + Δ.
// NaN when the track has fewer than 2 reversals.
double staircase_threshold(const Block& block, const std::vector<bool>& correct);

}  // namespace doorbench::study
