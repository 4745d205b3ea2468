#pragma once
// Power before the panel (docs/campaign.md, "Power"): `campaign plan --simulate N` runs the
// plan N times, each time with a fresh panel of simulated participants (study/
// participant_model.h, no device: the presentations are not played), and counts for each
// question how often the planned participants and trials detect the effect:
//  - pair: per pair of variants, the exact two-sided binomial test of "a chosen" against
//    "b chosen" over the panel's answers ("same" left out), detected when p < alpha;
//  - rating: per attribute and pair, the sign test of which variant was rated higher in
//    each trial (ties left out);
//  - jnd, constant stimuli: per level, the binomial test of "the comparison named stronger";
//  - jnd, staircase: no test; the panel's median threshold (study/staircase.h), summarised
//    over the panels (median and the 5th–95th percentiles); quest+ likewise with each
//    participant's posterior-mean threshold as a level (study/quest_plus.h);
//  - tune: no test; not reported.
// A detection rate comes with its Wilson score interval (95 %) for the N panels.
// Thread safety: free functions without shared state.
#include <cstdint>
#include <string>
#include <vector>

#include "study/campaign_file.h"
#include "study/participant_model.h"

namespace doorbench::study {

struct PowerLine {
  std::string block, question, what;         // what: "heavier vs reference", "level J*1.1"
  int panels = 0, detected = 0;              // detection counts (tests)
  double rate = 0.0, low = 0.0, high = 0.0;  // detected / panels and its Wilson interval
  bool is_threshold = false;                 // a staircase's summary instead of a test
  double threshold_median = 0.0, threshold_p05 = 0.0, threshold_p95 = 0.0;
  std::string text() const;
};

struct PowerOptions {
  int panels = 100;
  double alpha = 0.05;
  ParticipantModelOptions participant;
  std::string validate() const;
};

// Throws std::invalid_argument (options, a campaign the simulated participant cannot answer).
std::vector<PowerLine> simulate_power(const Campaign& campaign, std::uint64_t seed,
                                      const PowerOptions& options);

// The Wilson score interval of k successes in n at 95 % (z = 1.959964).
std::pair<double, double> wilson_interval(int k, int n);

}  // namespace doorbench::study
