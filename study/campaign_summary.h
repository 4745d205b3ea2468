#pragma once
// One line per block of what a campaign's trials.csv holds (the demo's summary; the
// panel's statistics are `campaign analyze`'s): counts only, no tests.
//   tune: how many tuned doors
//   pair: answers, how often each variant was chosen, "same"
//   rating: each variant's mean rating per attribute
//   jnd (constant stimuli): per level, how often the comparison was named stronger
//   jnd (staircase): the participants' median threshold (study/staircase.h)
//   jnd (quest+): the participants' median threshold and each one's posterior mean Weber
//     fraction with its 95 % credible interval (study/quest_plus.h)
// Rows of earlier attempts (a redo) are left out. Thread safety: a free function.
#include <string>
#include <vector>

#include "study/campaign_file.h"
#include "study/trials_table.h"

namespace doorbench::study {

std::vector<std::string> block_summaries(const Campaign& campaign, const TrialsTable& trials);

}  // namespace doorbench::study
