#pragma once
// A campaign file (docs/campaign.md, campaigns/example.toml): TOML naming the variants, the
// participants and the blocks of a study run across a panel. Read with toml++ like the rig
// files; every error is a CampaignError "FILE:LINE: field: detail" naming the file, the line
// and the field.
//
// Variants are written as one string each:
//   "base"                     the base door (campaign.base, or the reference door)
//   "file:PATH"                a parameter file (PATH relative to the campaign file)
//   "real"                     the real door on the bench (needs campaign.real_rig)
//   "heaviness*1.2"            steps from the base: a perceptual control of
//   "J*1.2,latch_effort*0.7"   analysis/perceptual_controls.h (sensory model) or a parameter
//                              of the campaign's model (J, k_inf, d1 ...; J_d, k_l ...) times
//                              a factor, applied left to right
// or, when a study varies what is seen and heard too, as a table
//   { door = "heaviness*1.2", scene = "scenes/oak.toml", sounds = "sounds/soft.toml" }
// whose `door` is one of the strings above and whose `scene` (a station scene file) and
// `sounds` (a sound set: the [sound] table of a TOML file, docs/station.md) are optional
// paths relative to the campaign file. The files must exist ("c.toml:7: variants.oak.scene:
// no such file 'scenes/oak.toml' (looked for /lab/study/scenes/oak.toml)"); what they hold
// is read by the station when it opens (study/ does not read scenes). The real door takes
// neither.
// Thread safety: free functions without shared state.
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "analysis/model/door_model.h"
#include "study/question.h"

namespace doorbench::study {

class CampaignError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One step from the base: `target` (a perceptual control or a parameter) times `factor`.
struct Step {
  std::string target;
  double factor = 1.0;
};

struct Variant {
  std::string name;
  std::string spec;  // as written: "base", "file:PATH", "real" or steps
  enum class Kind { kBase, kFile, kReal, kSteps } kind = Kind::kBase;
  std::filesystem::path file;  // kFile: resolved against the campaign file's folder
  std::vector<Step> steps;     // kSteps
  // What the station shows and plays for this variant: the paths as the campaign file spells
  // them (for trials.csv) and resolved against its folder; empty: the station's own.
  std::string scene, sounds;
  std::filesystem::path scene_file, sounds_file;
};

enum class BlockType { kTune, kPair, kRating, kJnd };
enum class JndMethod { kConstantStimuli, kStaircase, kQuestPlus };
std::string_view to_string(BlockType type);  // tune | pair | rating | jnd

struct Block {
  std::string name;
  BlockType type = BlockType::kPair;
  int line = 0;  // in the campaign file
  // tune: the start is the base with each tuning-key control times a factor drawn
  // log-uniformly in [1/(1+start_spread), 1+start_spread]
  double start_spread = 0.2;
  // pair
  QuestionKind question = QuestionKind::kPreference;  // preference, preference-2ac or identify-real
  std::vector<std::pair<std::string, std::string>> pairs;  // unordered; each played both ways
  // pair, rating and jnd (constant stimuli): how often the whole set of trials is repeated
  int repetitions = 1;
  // rating: every unordered pair of variants, rated on each attribute on 1..scale
  std::vector<std::string> attributes;
  int scale = 7;
  // jnd: the comparison is the base with `parameter` times a level (> 1), the standard the
  // base itself
  std::string parameter;
  JndMethod method = JndMethod::kConstantStimuli;
  std::vector<double> levels;  // constant stimuli
  // staircase (Levitt's transformed up-down on the increment level − 1): `down` correct
  // answers in a row make it smaller (÷ step_factor), one wrong answer larger (× step_factor)
  int down = 2;
  double start_level = 1.4, step_factor = 1.5, min_level = 1.01, max_level = 3.0;
  int trials = 20;  // staircase and quest+
  // quest+ (study/quest_plus.h): `quest_levels` comparison levels and `quest_thresholds`
  // threshold grid points over [min_level, max_level] (its defaults 1.01 and 2), lapse fixed
  int quest_levels = 30, quest_thresholds = 40;
  double lapse = 0.03;
};

struct Campaign {
  std::string name;
  std::uint64_t seed = 1;
  ModelKind model = ModelKind::kSensory;
  std::filesystem::path base_file;        // empty: the reference door
  std::filesystem::path real_rig;         // empty: no real door
  double presentation_s = 8.0;            // a presentation for a person (real time)
  double simulated_presentation_s = 1.0;  // on the simulated device in simulated time
  std::vector<Variant> variants;
  std::vector<std::string> participants;
  std::vector<Block> blocks;
  std::string source;  // the file's path, for messages
  std::string text;    // the file's text, kept with the plan

  const Variant* find_variant(std::string_view name) const;
};

// Parses a campaign; `folder` resolves relative paths. Throws CampaignError.
Campaign parse_campaign(std::string_view text, std::string_view source,
                        const std::filesystem::path& folder);
Campaign read_campaign(const std::filesystem::path& path);

// "" when `id` is a usable pseudonymous participant id, else why not (docs/campaign.md):
// 1 to 32 characters of letters, digits, '-' and '_', with at least one digit; no '@'
// (an e-mail), no space (a full name), no capitalised word of three or more letters
// (Firstname: "Anna07" is refused, "P07" and "sub-07" are not).
std::string participant_id_problem(std::string_view id);

// "J*1.2,latch_effort*0.7" -> steps; std::invalid_argument saying what is wrong.
std::vector<Step> parse_steps(std::string_view text);
std::string steps_text(const std::vector<Step>& steps);  // "J*1.2,latch_effort*0.7"

// The base door of the campaign (its model kind), the model a step list makes from a model
// (std::invalid_argument naming the step: unknown target, a result the model refuses), and
// a variant's model (kReal throws std::invalid_argument).
DoorModel base_model(const Campaign& campaign);
DoorModel apply_steps(const DoorModel& model, const std::vector<Step>& steps);
DoorModel variant_model(const Campaign& campaign, const Variant& variant);

}  // namespace doorbench::study
