#pragma once
// Ratings (docs/campaign.md, "Ratings and thresholds"): a cumulative-logit mixed model per
// attribute, fitted by maximum likelihood.
//
//   logit P(Y_ij <= k) = theta_k - (beta_v(ij) + sigma * u_i),   u_i ~ N(0, 1),
//
// Y_ij the rating (1..K) participant i gave in observation j, theta_1 < ... < theta_{K-1} the
// thresholds, beta_v the variant's effect (the first variant at 0; positive means rated
// higher) and sigma the spread of the participants' random intercepts. The random effect is
// integrated per participant by adaptive Gauss–Hermite quadrature around the conditional mode
// (one node is the Laplace approximation), as R's ordinal::clmm(..., nAGQ = n) does, with the
// same sign convention (McCullagh 1980; Agresti 2010; Christensen's ordinal). When sigma is
// estimated at 0 (no gain over the model without it) the fixed-effect model (ordinal::clm) is
// reported. Each effect has a Wald interval from the observed information.
//
// Categories nobody used are merged with their neighbours (their thresholds would be
// infinite; the variant effects are those of the merged scale).
//
// Errors: std::invalid_argument naming the attribute; the trials adapter throws
// TrialsTableError naming the file, line and field.
// Thread safety: pure functions without shared state.
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "study/trials_table.h"

namespace doorbench::study {

// One rating: participant `participant` rated variant `variant` `rating` on attribute
// `attribute`'s 1..`categories` scale.
struct RatingObservation {
  std::string participant;
  std::string attribute;
  int categories = 0;
  std::string variant;
  int rating = 0;
};

struct RatingsOptions {
  // Quadrature nodes per participant: 1 = Laplace approximation, n > 1 adaptive
  // Gauss–Hermite with n nodes (ordinal::clmm's nAGQ). 1..50.
  int quadrature_nodes = 10;
  double confidence = 0.95;  // of the Wald intervals, in (0, 1)
  // Variant order; the first is the reference at 0. Empty: order of first appearance.
  std::vector<std::string> variant_order;
  bool random_effect = true;  // false: the fixed-effect model (clm) only
  // Empty when usable, else the message naming the option.
  std::string validate() const;
};

struct VariantEffect {
  std::string variant;
  double estimate = 0.0;  // beta_v on the logit scale; 0 for the reference
  double std_error = 0.0;
  double ci_low = 0.0;
  double ci_high = 0.0;
};

struct AttributeRatings {
  std::string attribute;
  int categories = 0;                     // K of the scale as asked
  std::vector<int> used_categories;       // the ratings that occur, ascending
  std::vector<VariantEffect> effects;     // one per variant, the reference first
  std::vector<double> thresholds;         // theta between consecutive used categories
  double participant_sd = 0.0;            // sigma; 0 when the fixed-effect model was kept
  double participant_sd_std_error = 0.0;  // of sigma (0 when sigma is 0)
  bool random_effect = false;             // whether the mixed model was kept
  int quadrature_nodes = 0;
  double log_likelihood = 0.0;
  int observations = 0;
  int participants = 0;
  bool converged = false;
};

struct RatingsResult {
  std::vector<AttributeRatings> attributes;  // in order of first appearance
  // [{attribute, variant, estimate, ci_low, ci_high, std_error, reference}] — the
  // analysis.json `ratings` section (one row per attribute and variant).
  nlohmann::json to_json() const;
  // Per attribute: thresholds, participant_sd, model ("clmm" or "clm"), nodes, log-likelihood.
  nlohmann::json models_json() const;
};

// Fits one attribute's observations (all must share attribute and categories).
AttributeRatings fit_attribute_ratings(std::span<const RatingObservation> observations,
                                       const RatingsOptions& options = {});

// Fits every attribute. Throws std::invalid_argument when options are invalid or an
// attribute has fewer than two used categories or one variant only.
RatingsResult fit_ratings(std::span<const RatingObservation> observations,
                          const RatingsOptions& options = {});

// The rating rows of a trials table (question "rating:ATTRIBUTE:K", answer "R1 R2": R1 for
// the first presented variant, R2 for the second). Refused with the row's line: a K that is
// not an integer 2..100, an answer that is not two integers in 1..K.
std::vector<RatingObservation> rating_observations(const TrialsTable& table);

}  // namespace doorbench::study
