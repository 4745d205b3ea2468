#pragma once
// A simulated participant (docs/campaign.md, "Simulated participants"): a pure model of how
// one person answers the campaign's questions, with no device in it, so that the run
// (--respondent sim:SEED), the power simulation (campaign plan --simulate N) and the
// statistics' coverage studies share it.
//
// What it perceives: the five sensations the tuning keys move (analysis/perceptual_controls.h:
// heaviness, latch_effort, closing_effort, smoothness, snap) of the door presented, each on a
// log scale with Gaussian noise. The noise's σ is set from the participant's Weber fraction w
// so that in a two-interval comparison the difference ln(1+w) is told right 75 % of the time:
// σ = ln(1+w) / (√2 · 0.6745). (A parameter outside those five, in a jnd block, is perceived
// by its own value with the default Weber fraction other_weber.)
//
// How it answers:
//  - stronger:PARAM: names the presentation whose noisy percept is larger; a position bias b
//    (in the difference's σ, > 0 favours presentation 1) is added; with probability lapse it
//    answers at random instead.
//  - preference / preference-2ac / identify-real: the utility of a percept is minus half the
//    squared distance from the participant's preferred door, in JNDs summed over the five
//    sensations; it prefers the higher utility (bias and lapse as above); in 2-AC it answers
//    "same" when the two utilities differ by less than same_band. identify-real answers at
//    random (the model holds no notion of a real door).
//  - rating:ATTRIBUTE:K: an attribute naming a sensation (heav/light → heaviness; latch →
//    latch_effort; clos → closing_effort; smooth/rough/jerk/friction → smoothness; snap →
//    snap; the first word is the scale's high end) is rated by its percept, mid-scale at the
//    base door, rating_steps_per_jnd steps per JND; any other attribute (pleasant, ...) by
//    the utility. Each rating gets Gaussian noise of rating_noise steps.
//  - tune: presses the tuning keys (study/tuning_keys.h) one at a time, always on the
//    sensation furthest from its preference in JNDs, until every one is within one JND or
//    a key is refused twice or max_presses.
//
// Each participant's values are drawn from its seed (study/random_stream.h): Weber fractions
// around the typical ones (log-normal, weber_spread), the preferred door around the
// population's (log-normal, preference_spread_jnd JNDs), lapse uniform on [0, 2·lapse_rate],
// bias normal with sd position_bias_sd.
// Thread safety: const objects may be shared; a draw's generator belongs to its caller.
#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/door_model.h"

namespace doorbench::study {

inline constexpr int kSensations = 5;
// heaviness, latch_effort, closing_effort, smoothness, snap
extern const std::array<std::string_view, kSensations> kSensationNames;

struct ParticipantModelOptions {
  // Typical Weber fractions (docs/campaign.md gives the sources): inertia 10 %, the latch's
  // and the closing's stiffness-made forces 17 %, friction 20 %, the snap (a damping) 20 %.
  std::array<double, kSensations> typical_weber{0.10, 0.17, 0.17, 0.20, 0.20};
  double other_weber = 0.20;
  double weber_spread = 0.25;  // sd of ln(w / typical) across participants
  // The population's preferred door as factors on the base's sensations (1: the base).
  std::array<double, kSensations> population_preference{1.0, 1.0, 1.0, 1.0, 1.0};
  double preference_spread_jnd = 1.5;  // sd of a participant's preference around it, JNDs
  double lapse_rate = 0.03;            // mean; each participant's is uniform on [0, 2×]
  double position_bias_sd = 0.2;       // in the decision's σ
  double same_band = 1.5;              // 2-AC: utilities closer than this are "same"
  double rating_steps_per_jnd = 0.5;
  double rating_noise = 0.5;     // scale steps
  int max_presses = 60;          // tune
  std::string validate() const;  // "" or one line naming the option
};

struct SimulatedParticipant {
  std::array<double, kSensations> weber{};
  std::array<double, kSensations> preferred_log{};  // ln of the preferred sensations
  std::array<double, kSensations> base_log{};       // ln of the base door's
  double lapse = 0.0, bias = 0.0;
  ParticipantModelOptions options;
};

// A participant drawn from `seed` around the sensory `base` door (std::invalid_argument for
// a physical model or bad options).
SimulatedParticipant draw_participant(std::uint64_t seed, const DoorModel& base,
                                      const ParticipantModelOptions& options = {});

// ln of the five sensations of a sensory model.
std::array<double, kSensations> sensations(const DoorModel& model);

// The answer to one question about two presentations, as trials.csv spells it: "1", "2",
// "same" or "r1 r2". `question` is one of PlanRow's; `random` is the trial's own stream.
// std::invalid_argument for a question it cannot answer (tune: see tune_door).
std::string answer_question(const SimulatedParticipant& participant, std::string_view question,
                            const DoorModel& first, const DoorModel& second,
                            std::mt19937_64& random);

struct TuneOutcome {
  DoorModel model;
  std::string keys;  // the keys pressed, in order
};
TuneOutcome tune_door(const SimulatedParticipant& participant, const DoorModel& start,
                      std::mt19937_64& random);

}  // namespace doorbench::study
