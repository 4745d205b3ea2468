#pragma once
// Tuning (docs/campaign.md, "Ratings and thresholds"): the doors the participants tuned in
// `tune` blocks, the panel's distribution per parameter in perceptual steps, and whether the
// panel splits into two groups.
//
// Per parameter (positive values): the panel's geometric mean with a 95 % t interval on
// ln value, the spread (SD of ln value), and both in perceptual steps: ln values divided by
// ln(1 + w), w the parameter's Weber fraction — the panel's measured JND where a jnd block
// measured that parameter (pass it in TuningOptions::measured_weber), else a typical
// published value (inertia 10 %, stiffness 15 %, viscosity and friction 20 %: the typical
// haptic values the campaign issue names), else none (no steps).
// Parameters that are not all positive are summarised on the linear scale, without steps.
//
// Clusters: 2-means on the doors in perceptual steps (the parameters that have steps and
// vary), every pair of doors tried as the starting centres; the split is called real when
// the Bayesian information criterion of two spherical Gaussian groups (shared variance, the
// k-means assignment, group shares) is lower than that of one, each group has at least
// min_cluster_size doors, and the groups' centres lie at least min_separation_steps apart
// (Euclidean, in perceptual steps): a split people could feel. (BIC on the hard assignment
// alone calls a split in about 12 % of unimodal panels of 20.)
//
// Errors: std::invalid_argument naming the parameter or the door; the trials adapter throws
// TrialsTableError naming the file's line, and passes on ParameterFileError naming the
// parameter file. Thread safety: pure functions without shared state (the adapter reads files).
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "study/statistics/thresholds.h"
#include "study/trials_table.h"

namespace doorbench::study {

struct TunedDoor {
  std::string participant;
  std::string file;  // the parameter file's name as the trials table gives it ("" if none)
  std::vector<std::pair<std::string, double>> parameters;  // name, value
};

struct TuningOptions {
  double confidence = 0.95;
  std::map<std::string, double> measured_weber;  // parameter -> the panel's measured Weber fraction
  int min_cluster_size = 2;
  double min_separation_steps = 2.0;  // the groups' centres this far apart at least
  std::string validate() const;       // empty when usable, else the message naming the option
};

struct ParameterDistribution {
  std::string parameter;
  bool log_scale = true;  // false: some value is not positive
  int doors = 0;
  double centre = 0.0;                 // geometric mean (log scale) or mean (linear)
  double spread = 0.0;                 // SD of ln value (log scale) or of the value (linear)
  double ci_low = 0.0, ci_high = 0.0;  // t interval of the centre
  double min = 0.0, max = 0.0;
  std::optional<double> weber_fraction;
  std::string weber_source;             // "measured (jnd)", "typical: inertia 10%", ..., or "none"
  std::optional<double> spread_steps;   // spread / ln(1 + w)
  std::optional<double> ci_half_steps;  // half the interval's width on ln, in steps
};

struct TuningClusters {
  bool split = false;
  double bic_one = 0.0, bic_two = 0.0;
  std::vector<std::string> dimensions;                 // the parameters clustered on
  std::vector<int> group;                              // per door, 0 or 1 (all 0 when not split)
  std::vector<std::map<std::string, double>> centres;  // per group, geometric means
  std::map<std::string, double> separation_steps;      // per dimension, group 1 - group 0
  double separation = 0.0;  // between the 2-means centres, Euclidean in steps (also when not split)
};

struct TuningResult {
  std::vector<TunedDoor> doors;
  std::vector<ParameterDistribution> parameters;
  TuningClusters clusters;
  // The analysis.json `tuning` section (schema in docs/campaign.md):
  // {doors: [{participant, file, parameters: {NAME: value}}],
  //  parameters: [{parameter, scale, doors, centre, spread, ci_low, ci_high, min, max,
  //                weber_fraction, weber_source, spread_steps, ci_half_steps}],
  //  clusters: {split, rule, bic_one, bic_two, dimensions, groups: [{participants, centre}],
  //             separation_steps}}
  nlohmann::json to_json() const;
};

// The typical published Weber fraction for a parameter name and its source's words, or
// nullopt when none applies (angles, geometry, shapes).
std::optional<std::pair<double, std::string>> typical_weber_fraction(const std::string& parameter);

// The panel's measured Weber fractions (pooled fits) by parameter, for TuningOptions.
std::map<std::string, double> measured_weber_fractions(const ThresholdsResult& thresholds);

// Throws std::invalid_argument when options are invalid, when no door is given, or when the
// doors do not all name the same parameters.
TuningResult analyze_tuning(std::span<const TunedDoor> doors, const TuningOptions& options = {});

// The tuned doors of a trials table's `tune` rows: each answer is a parameter file read
// relative to `folder` (analysis/parameter_file.h): the sensory section's parameters, then
// the physical section's (a physical name that the sensory section has too is prefixed
// "physical."). A participant who tuned several times keeps the last. Refused with the
// row's line: an empty answer.
std::vector<TunedDoor> tuned_doors(const TrialsTable& table, const std::filesystem::path& folder);

// The plots (analysis/svg_plot.h): each door in perceptual steps from the panel's centre,
// one line per door across the parameters that have steps (coloured by group when the
// panel splits); written whole or not at all. Throws std::invalid_argument when no
// parameter has steps.
std::string render_tuning_plot(const TuningResult& tuning);
void write_tuning_plot(const std::string& path, const TuningResult& tuning);

}  // namespace doorbench::study
