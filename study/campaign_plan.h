#pragma once
// A campaign's plan (docs/campaign.md, "The plan"): every participant's trials, in order,
// written out whole before anything runs (plan.csv), from the campaign file and a seed.
// The same campaign text and seed give the same plan on any machine (study/random_stream.h).
//
// Per participant i (0-based, in the campaign's order): the blocks in the order of row
// i mod rows of a Williams design over the blocks (study/latin_square.h); within a block:
//  - tune: one trial; `first` is the randomised start as steps from the base
//    ("heaviness*1.083,latch_effort*0.912,...");
//  - pair: the block's pairs in the order of row i mod R of a Williams design over the
//    pairs (randomly relabelled once per campaign and block from the seed), forwards, then
//    backwards with every presentation order swapped, × repetitions: each pair in both
//    presentation orders, each pair in each position equally often and each pair directly
//    after each other pair equally often over a multiple of R participants; the presentation
//    orders (so each variant in each place) balanced over a multiple of 2R;
//  - rating: the same design, one pass per repetition × attribute (question
//    rating:ATTRIBUTE:K; the attributes of a repetition in cyclic order from attribute
//    i mod A), passes alternately forwards and backwards, each pair's presentation order
//    swapped from pass to pass;
//  - jnd, constant stimuli: each level × repetitions, the comparison ("J*1.1") first in half
//    of them and the standard ("J*1") in the other, in an order shuffled by the
//    participant's and the block's own substream; question stronger:PARAM;
//  - jnd, staircase: `trials` slots whose comparison is written "J*?": its level is decided at
//    run time from the answers before it (Levitt's rule, study/staircase.h); only the
//    positions (comparison first or second, balanced and shuffled) are planned.
//  - jnd, quest+: the same slots, each level chosen at run time by QUEST+ (study/quest_plus.h).
// Thread safety: free functions without shared state.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "study/campaign_file.h"
#include "study/trials_table.h"

namespace doorbench::study {

struct PlanRow {
  std::string participant;
  std::string block;
  int trial = 0;         // 1-based, the participant's running order over all blocks
  std::string question;  // preference | preference-2ac | identify-real | stronger:PARAM |
                         // rating:ATTRIBUTE:K | tune
  std::string first, second;
  int block_trial = 0;  // 1-based within the block
};

struct Plan {
  std::uint64_t seed = 0;
  std::vector<PlanRow> rows;  // participant by participant, each in running order
  // The rows of one participant (empty when the plan has no such participant).
  std::vector<PlanRow> of(const std::string& participant) const;
};

// The plan of `campaign` with `seed`. std::invalid_argument when a tune start cannot be drawn.
Plan make_plan(const Campaign& campaign, std::uint64_t seed);

// How many participants make the counterbalancing exact (docs/campaign.md,
// "Counterbalancing"): the least common multiple of the rows of the block order's design
// and, for each pair or rating block, of 2 × its design's rows (and its attribute count).
// `parts` names each: "block order 10", "block 'pair' 12", ...
struct BalancedCount {
  long long participants = 1;
  std::vector<std::string> parts;
};
BalancedCount balanced_participant_count(const Campaign& campaign);
// "" when the campaign's participant count is a multiple of balanced_participant_count,
// else one line saying so, e.g. "note: 13 participants; the counterbalancing is exact for a
// multiple of 60 (block order 10, block 'pair' 12, block 'rating' 12); the first 13 rows of
// each design are used (docs/campaign.md, Counterbalancing)".
std::string balance_note(const Campaign& campaign);

// plan.csv: participant,block,trial,question,first,second,block_trial (RFC 4180).
std::string plan_csv(const Plan& plan);
// Reads it back; TrialsTableError (study/trials_table.h) naming file and line when broken.
Plan read_plan_csv(const std::filesystem::path& path, std::uint64_t seed);

// FNV-1a, 64 bits, as 16 hex digits: the identity of a plan's and a campaign's text.
std::string fnv1a64_hex(std::string_view text);

// The comparison's name in a jnd block: "J*1.1" (the level with up to 4 decimals, trailing
// zeros cut); the standard is "J*1".
std::string jnd_stimulus_name(const std::string& parameter, double level);

// The campaign folder (`campaign plan --out DIR`): campaign.toml (the file as given),
// plan.csv, plan-id.txt (campaign name, seed, source folder, the hashes of plan.csv and of
// the campaign text). write_campaign_folder refuses a non-empty DIR unless `overwrite`
// (OutputRefused), writes each file through a temporary file.
struct PlanIdentity {
  std::string campaign;
  std::uint64_t seed = 0;
  std::string plan_hash, campaign_hash;
  std::filesystem::path campaign_folder;  // where relative paths of the campaign resolve
  std::string text() const;
};
void write_campaign_folder(const std::filesystem::path& dir, const Campaign& campaign,
                           const Plan& plan, bool overwrite);
// Reads plan-id.txt and checks plan.csv against its hash (CampaignError when it differs).
PlanIdentity read_plan_identity(const std::filesystem::path& dir);
// The campaign and the plan of a folder.
struct CampaignFolder {
  std::filesystem::path dir;
  PlanIdentity identity;
  Campaign campaign;
  Plan plan;
};
CampaignFolder open_campaign_folder(const std::filesystem::path& dir);

// The variant a preference scale puts at worth 0 when the analyst names none: the first
// variant of `input`'s campaign.toml (the plan's order) when `input` is a readable campaign
// folder and `table` compares that variant in a preference question; else "" (the first
// variant in the table). Never throws for an unreadable folder (its table alone decides).
std::string plan_reference_variant(const std::filesystem::path& input, const TrialsTable& table);

}  // namespace doorbench::study
