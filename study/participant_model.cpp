#include "study/participant_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "analysis/model/perceptual_controls.h"
#include "study/question.h"
#include "study/random_stream.h"
#include "study/tuning_keys.h"

namespace doorbench::study {

const std::array<std::string_view, kSensations> kSensationNames = {
    "heaviness", "latch_effort", "closing_effort", "smoothness", "snap"};

namespace {

constexpr double kQuartile = 0.6744897501960817;  // Φ⁻¹(0.75)

double sigma_of(double weber) {
  return std::log1p(weber) / (std::sqrt(2.0) * kQuartile);
}

// The sensation a jnd parameter is felt by; -1: by its own value.
int sensation_of(std::string_view name) {
  static const std::array<std::array<std::string_view, 2>, kSensations> parameters = {
      {{"J", "J_d"}, {"k_inf", "k_inf"}, {"k_lock", "k_lock"}, {"d1", "T_h"}, {"c", "c"}}};
  for (int s = 0; s < kSensations; ++s) {
    if (name == kSensationNames[s] || name == parameters[s][0] || name == parameters[s][1])
      return s;
  }
  return -1;
}

// The rating attribute's sensation; -1: the utility (pleasantness).
int attribute_sensation(std::string_view attribute) {
  const std::string_view first = attribute.substr(0, attribute.find('-'));
  const auto has = [&](std::string_view word) {
    return first.find(word) != std::string_view::npos;
  };
  if (has("heav") || has("light")) return 0;
  if (has("unlatch") || has("latch")) return 1;
  if (has("clos")) return 2;
  if (has("smooth") || has("rough") || has("jerk") || has("friction")) return 3;
  if (has("snap")) return 4;
  return -1;
}

std::array<double, kSensations> perceive(const SimulatedParticipant& p, const DoorModel& model,
                                         std::mt19937_64& random) {
  std::array<double, kSensations> percept = sensations(model);
  for (int s = 0; s < kSensations; ++s)
    percept[s] += sigma_of(p.weber[s]) * standard_normal(random);
  return percept;
}

double utility(const SimulatedParticipant& p, const std::array<double, kSensations>& percept) {
  double sum = 0.0;
  for (int s = 0; s < kSensations; ++s) {
    const double jnds = (percept[s] - p.preferred_log[s]) / std::log1p(p.weber[s]);
    sum += jnds * jnds;
  }
  return -0.5 * sum;
}

bool lapses(const SimulatedParticipant& p, std::mt19937_64& random) {
  return uniform_open01(random) < p.lapse;
}

std::string choice(bool second) {
  return second ? "2" : "1";
}

std::string answer_stronger(const SimulatedParticipant& p, std::string_view parameter,
                            const DoorModel& first, const DoorModel& second,
                            std::mt19937_64& random) {
  const int s = sensation_of(parameter);
  double a = 0.0, b = 0.0, sigma = 0.0;
  if (s >= 0) {
    a = sensations(first)[s];
    b = sensations(second)[s];
    sigma = sigma_of(p.weber[s]);
  } else {
    const std::optional<int> index = first.find_parameter(parameter);
    if (!index)
      throw std::invalid_argument("stronger:" + std::string(parameter) +
                                  ": not a parameter of the model");
    a = std::log(std::abs(first.parameter_values()[*index]));
    b = std::log(std::abs(second.parameter_values()[*index]));
    sigma = sigma_of(p.options.other_weber);
  }
  const double noisy_a = a + sigma * standard_normal(random);
  const double noisy_b = b + sigma * standard_normal(random);
  const double decision = noisy_b - noisy_a - p.bias * sigma * std::sqrt(2.0);
  if (lapses(p, random)) return choice(uniform_below(random, 2) == 1);
  return choice(decision > 0.0);
}

int rating_of(const SimulatedParticipant& p, int sensation, int scale,
              const std::array<double, kSensations>& percept, std::mt19937_64& random) {
  const double middle = 0.5 * (scale + 1);
  double value = 0.0;
  if (sensation >= 0) {
    value = middle + p.options.rating_steps_per_jnd * (percept[sensation] - p.base_log[sensation]) /
                         std::log1p(p.weber[sensation]);
  } else {
    value = scale - p.options.rating_steps_per_jnd * std::sqrt(-2.0 * utility(p, percept));
  }
  value += p.options.rating_noise * standard_normal(random);
  return static_cast<int>(std::clamp(std::lround(value), 1L, static_cast<long>(scale)));
}

}  // namespace

std::string ParticipantModelOptions::validate() const {
  for (double w : typical_weber) {
    if (!(w > 0.0 && w < 5.0)) return "typical Weber fractions must be above 0 and below 5";
  }
  if (!(other_weber > 0.0 && other_weber < 5.0)) return "other_weber must be above 0 and below 5";
  if (!(weber_spread >= 0.0 && weber_spread < 2.0)) return "weber_spread must be 0 to 2";
  for (double f : population_preference) {
    if (!(f > 0.0 && std::isfinite(f))) return "population_preference factors must be above 0";
  }
  if (!(preference_spread_jnd >= 0.0 && preference_spread_jnd < 100.0))
    return "preference_spread_jnd must be 0 to 100";
  if (!(lapse_rate >= 0.0 && lapse_rate <= 0.5)) return "lapse_rate must be 0 to 0.5";
  if (!(position_bias_sd >= 0.0 && position_bias_sd < 10.0))
    return "position_bias_sd must be 0 to 10";
  if (!(same_band >= 0.0)) return "same_band must be 0 or more";
  if (!(rating_steps_per_jnd > 0.0) || !(rating_noise >= 0.0))
    return "rating_steps_per_jnd must be above 0, rating_noise 0 or more";
  if (max_presses < 0 || max_presses > 10000) return "max_presses must be 0 to 10000";
  return "";
}

std::array<double, kSensations> sensations(const DoorModel& model) {
  std::array<double, kSensations> result{};
  for (int s = 0; s < kSensations; ++s) {
    const perceptual::Control control = *perceptual::find(kSensationNames[s]);
    result[s] = std::log(std::max(std::abs(perceptual::read(model, control)), 1e-12));
  }
  return result;
}

SimulatedParticipant draw_participant(std::uint64_t seed, const DoorModel& base,
                                      const ParticipantModelOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("participant model: " + problem);
  }
  if (base.kind() != ModelKind::kSensory) {
    throw std::invalid_argument(
        "a simulated participant perceives the sensory model's controls (the campaign's model is " +
        std::string(to_string(base.kind())) + ")");
  }
  std::mt19937_64 random(substream_seed(seed, 0, 0, Purpose::kParticipantModel));
  SimulatedParticipant p;
  p.options = options;
  p.base_log = sensations(base);
  for (int s = 0; s < kSensations; ++s) {
    p.weber[s] =
        options.typical_weber[s] * std::exp(options.weber_spread * standard_normal(random));
    p.preferred_log[s] =
        p.base_log[s] + std::log(options.population_preference[s]) +
        options.preference_spread_jnd * std::log1p(p.weber[s]) * standard_normal(random);
  }
  p.lapse = 2.0 * options.lapse_rate * uniform_open01(random);
  p.bias = options.position_bias_sd * standard_normal(random);
  return p;
}

std::string answer_question(const SimulatedParticipant& p, std::string_view question_text,
                            const DoorModel& first, const DoorModel& second,
                            std::mt19937_64& random) {
  const std::optional<Question> question = Question::parse(question_text);
  if (!question || question->kind == QuestionKind::kTune) {
    throw std::invalid_argument("the simulated participant cannot answer '" +
                                std::string(question_text) + "'");
  }
  if (question->kind == QuestionKind::kStronger)
    return answer_stronger(p, question->subject, first, second, random);
  if (question->kind == QuestionKind::kRating) {
    const int sensation = attribute_sensation(question->subject);
    const auto a = perceive(p, first, random), b = perceive(p, second, random);
    const int r1 = rating_of(p, sensation, question->scale, a, random);
    const int r2 = rating_of(p, sensation, question->scale, b, random);
    return std::to_string(r1) + " " + std::to_string(r2);
  }
  if (question->kind == QuestionKind::kIdentifyReal) return choice(uniform_below(random, 2) == 1);
  const double u1 = utility(p, perceive(p, first, random));
  const double u2 = utility(p, perceive(p, second, random));
  if (lapses(p, random)) return choice(uniform_below(random, 2) == 1);
  const double decision = u2 - u1 - p.bias;
  if (question->kind == QuestionKind::kPreference2ac && std::abs(u2 - u1) < p.options.same_band)
    return "same";
  return choice(decision > 0.0);
}

TuneOutcome tune_door(const SimulatedParticipant& p, const DoorModel& start,
                      std::mt19937_64& random) {
  TuneOutcome outcome{start, ""};
  std::array<int, kSensations> refused{};
  for (int press = 0; press < p.options.max_presses; ++press) {
    const auto percept = perceive(p, outcome.model, random);
    int worst = -1;
    double worst_jnds = 1.0;
    for (int s = 0; s < kSensations; ++s) {
      const double jnds = std::abs(percept[s] - p.preferred_log[s]) / std::log1p(p.weber[s]);
      if (refused[s] < 2 && jnds > worst_jnds) {
        worst = s;
        worst_jnds = jnds;
      }
    }
    if (worst < 0) break;
    const bool increase = percept[worst] < p.preferred_log[worst];
    char key = 0;
    for (const TuningKey& k : tuning_keys()) {
      if (k.control == *perceptual::find(kSensationNames[worst]) && k.increase == increase)
        key = k.key;
    }
    const KeyOutcome result = apply_key(outcome.model, key);
    outcome.keys += key;
    if (result.model) {
      outcome.model = *result.model;
    } else {
      ++refused[worst];
    }
  }
  return outcome;
}

}  // namespace doorbench::study
