// The demo's simulated campaign (the same function `doorbench demo` runs) through the
// commands a user types: `campaign analyze` on its folder, then `spec --campaign` on that
// analysis. The perceptual tolerance table's numbers are checked against a direct Monte Carlo
// written here (its own tolerance draws, its own JNDs read from analysis.json, its own
// criterion); the TO-BE door of both routes (the favourite variant's file, the tuned doors'
// centre) against the trials table.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "analysis/design/felt_quantities.h"
#include "analysis/model/parameter_file.h"
#include "app/commands.h"
#include "fixtures/temp_dir.h"
#include "study/statistics/analysis_for_spec.h"
#include "study/trials_table.h"
#include "tests/support/run_doorbench.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;
using json = nlohmann::json;

namespace {

// The demo's campaign in dir/campaign/folder, analysed into dir/analysis by the command.
void demo_campaign_analysed(const TempDir& dir) {
  std::ostringstream demo_output;
  doorbench::app::run_demo_campaign(dir / "campaign", demo_output);
  const auto run =
      run_doorbench_shell("campaign analyze '" + (dir / "campaign" / "folder").string() +
                              "' --out '" + (dir / "analysis").string() + "' --no-pdf",
                          dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
}

json read_json(const std::filesystem::path& path) {
  return json::parse(doorbench::read_text_file(path));
}

// "J=1.14 k=40 ..." as name -> value (the table's rendered parameters, read here).
std::map<std::string, double> rendered(const std::string& text) {
  std::map<std::string, double> values;
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    const auto equals = word.find('=');
    values[word.substr(0, equals)] = std::stod(word.substr(equals + 1));
  }
  return values;
}

// The variant of largest worth in analysis.json.
std::string favourite_of(const json& analysis) {
  std::string best;
  double worth = -1e300;
  for (const json& row : analysis.at("preference_scale")) {
    if (row.at("worth").get<double>() > worth) {
      worth = row.at("worth").get<double>();
      best = row.at("variant").get<std::string>();
    }
  }
  return best;
}

// The test's own criterion: over the JND when the ratio leaves [1/(1+w), 1+w] (or flips sign).
bool over_jnd(double value, double nominal, double w) {
  const double ratio = value / nominal;
  return !(ratio >= 1.0 / (1.0 + w) && ratio <= 1.0 + w);
}

// The JND each felt quantity should get from this analysis, by the rule of docs/design-spec.md
// written out here: the panel's pooled psychometric JND of latch_effort stands for the peak
// force to unlatch; the rest are typical (stiffness 15 %, friction 20 %). The demo campaign
// measures J and latch_effort only.
std::map<std::string, double> expected_jnds(const json& analysis) {
  std::map<std::string, double> jnds{
      {"peak_unlatch_force_N", 0.15},     {"peak_latch_force_N", 0.15},
      {"friction_near_closed_N", 0.20},   {"friction_open_N", 0.20},
      {"free_movement_friction_N", 0.20}, {"balance_force_N", 0.15}};
  for (const json& row : analysis.at("jnd")) {
    if (row.at("participant") == "panel" && row.at("parameter") == "latch_effort" &&
        row.at("method") == "psychometric fit, pooled") {
      jnds["peak_unlatch_force_N"] = row.at("weber_fraction").get<double>();
    }
  }
  return jnds;
}

struct DirectShares {
  std::map<std::string, int> doors, over;
};

// Doors drawn here from the tolerances spec.json lists (normal: the band is ±3σ, redrawn
// beyond it; uniform over the band; clamped to the parameter's bounds), their felt quantities
// in the standard run, counted over the JNDs.
DirectShares direct_monte_carlo(const DoorModel& design, const json& tolerances,
                                const std::map<std::string, double>& jnds, int draws,
                                std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const doorbench::FeltQuantities nominal = doorbench::felt_quantities(design);
  DirectShares shares;
  for (int s = 0; s < draws; ++s) {
    std::vector<double> values(design.parameter_values().begin(), design.parameter_values().end());
    for (const json& t : tolerances) {
      const int i = *design.find_parameter(t.at("name").get<std::string>());
      const double plus_minus = t.at("plus_minus").get<double>();
      const double band =
          t.at("percent").get<bool>() ? std::abs(values[i]) * plus_minus / 100.0 : plus_minus;
      double unit = 0;
      if (t.at("distribution") == "uniform") {
        unit = uniform(random);
      } else {
        do {
          unit = normal(random) / 3.0;
        } while (std::abs(unit) > 1.0);
      }
      const auto bounds = design.parameter_bounds()[i];
      values[i] = std::clamp(values[i] + band * unit, bounds.lower, bounds.upper);
    }
    doorbench::FeltQuantities door;
    try {
      door = doorbench::felt_quantities(design.with_parameter_values(values));
    } catch (const std::exception&) {
      continue;  // a door the simulation cannot run is not counted (nor in the table)
    }
    for (const auto& info : doorbench::kFeltQuantities) {
      const double value = door.*info.member;
      if (!std::isfinite(value)) continue;
      ++shares.doors[std::string(info.name)];
      if (over_jnd(value, nominal.*info.member, jnds.at(std::string(info.name))))
        ++shares.over[std::string(info.name)];
    }
  }
  return shares;
}

// The table's share against the direct one: within four standard errors of the difference
// of two binomial estimates (the pooled share smoothed by one door each way, so that two
// zeros still have a spread); the table's Wilson interval recomputed here.
void check_against_direct(const json& row, int direct_doors, int direct_over,
                          const std::string& what) {
  const int doors = row.at("doors").get<int>();
  const int over = row.at("felt_different").get<int>();
  const double table = row.at("share").get<double>();
  const double direct = static_cast<double>(direct_over) / direct_doors;
  const double pooled = (over + direct_over + 1.0) / (doors + direct_doors + 2.0);
  const double se = std::sqrt(pooled * (1 - pooled) * (1.0 / direct_doors + 1.0 / doors));
  INFO(what << ": table " << table << " (" << over << " of " << doors << "), direct " << direct
            << " (" << direct_over << " of " << direct_doors << ")");
  CHECK(std::abs(table - direct) <= 4 * se);
  CHECK(table == static_cast<double>(over) / doors);
  const double z = 1.959963984540054, n = doors, p = table;
  const double centre = (p + z * z / (2 * n)) / (1 + z * z / n);
  const double half = z / (1 + z * z / n) * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n));
  CHECK_THAT(row.at("ci_low").get<double>(),
             Catch::Matchers::WithinAbs(std::max(0.0, centre - half), 1e-9));
  CHECK_THAT(row.at("ci_high").get<double>(),
             Catch::Matchers::WithinAbs(std::min(1.0, centre + half), 1e-9));
}

}  // namespace

TEST_CASE("campaign analyze writes each ranked variant's parameter file from the trials table",
          "[campaign][spec]") {
  TempDir dir("campaign_chain_variants");
  demo_campaign_analysed(dir);
  const json analysis = read_json(dir / "analysis" / "analysis.json");
  const auto table =
      doorbench::study::read_trials_table(dir / "campaign" / "folder" / "trials.csv");
  REQUIRE(analysis.at("preference_scale").size() == 4);
  // A campaign folder's scale has the campaign file's first variant at 0 (the plan's order),
  // not the table's first.
  for (const json& row : analysis.at("preference_scale")) {
    INFO(row.dump());
    CHECK((row.at("interval") == "reference") == (row.at("variant") == "reference"));
    if (row.at("variant") == "reference") CHECK(row.at("worth") == 0.0);
  }
  for (const json& row : analysis.at("preference_scale")) {
    const std::string variant = row.at("variant").get<std::string>();
    INFO(variant);
    REQUIRE(row.contains("file"));
    CHECK(row.at("file") == "variants/" + variant + ".json");
    // The file's door has the values the table rendered for the variant (to the 6 digits
    // the table keeps).
    const DoorModel door = doorbench::load_model(
        doorbench::ModelKind::kSensory, dir / "analysis" / row.at("file").get<std::string>(), "");
    std::map<std::string, double> from_table;
    for (std::size_t r = 0; r < table.rows.size() && from_table.empty(); ++r) {
      if (table.value(r, "first") == variant)
        from_table = rendered(table.value(r, "first_parameters"));
    }
    REQUIRE(from_table.size() == static_cast<std::size_t>(door.parameter_count()));
    for (const auto& [name, value] : from_table) {
      CHECK_THAT(door.parameter_values()[*door.find_parameter(name)], WithinRel(value, 1e-12));
    }
  }
}

TEST_CASE("spec --campaign's TO-BE door is the favourite's file or else the tuned doors' centre",
          "[campaign][spec]") {
  TempDir dir("campaign_chain_tobe");
  demo_campaign_analysed(dir);
  const json analysis = read_json(dir / "analysis" / "analysis.json");
  const std::string favourite = favourite_of(analysis);
  const DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  std::string source;
  const DoorModel chosen = doorbench::campaign_tobe_model(
      doorbench::study::read_campaign_for_spec(dir / "analysis"), asis, source);
  CHECK(source == "the panel's favourite variant " + favourite +
                      " (largest worth on the preference scale), its parameter file " +
                      (dir / "analysis" / "variants" / (favourite + ".json")).string() +
                      ", opened and closed by the virtual hand");
  const auto table =
      doorbench::study::read_trials_table(dir / "campaign" / "folder" / "trials.csv");
  std::map<std::string, double> favourite_values;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (table.value(r, "second") == favourite)
      favourite_values = rendered(table.value(r, "second_parameters"));
  }
  REQUIRE_FALSE(favourite_values.empty());
  CHECK(chosen.kind() == doorbench::ModelKind::kSensory);
  for (const auto& [name, value] : favourite_values) {
    CHECK_THAT(chosen.parameter_values()[*chosen.find_parameter(name)], WithinRel(value, 1e-12));
  }

  // The same analysis from a table without the rendered parameters (as one written by
  // hand): no files, and the TO-BE door is the geometric mean of the tuned doors, computed
  // here from the tuned files the table names.
  std::string stripped = "participant,block,trial,question,first,second,answer\n";
  std::vector<std::string> tuned_files;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    std::vector<std::string> fields;
    for (const char* column :
         {"participant", "block", "trial", "question", "first", "second", "answer"})
      fields.push_back(table.value(r, column));
    stripped += doorbench::study::csv_row(fields);
    if (table.value(r, "question") == "tune") tuned_files.push_back(table.value(r, "answer"));
  }
  dir.write("campaign/folder/by-hand.csv", stripped);
  const auto run = run_doorbench_shell("campaign analyze '" +
                                           (dir / "campaign" / "folder" / "by-hand.csv").string() +
                                           "' --out '" + (dir / "by-hand").string() + "' --no-pdf",
                                       dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Contains(" and 0 variant parameter file(s)\n"));
  const json by_hand = read_json(dir / "by-hand" / "analysis.json");
  CHECK_FALSE(by_hand.at("preference_scale").at(0).contains("file"));
  // A table alone: its first variant in a pair is at 0.
  std::string first_in_table;
  for (std::size_t r = 0; r < table.rows.size() && first_in_table.empty(); ++r) {
    if (table.value(r, "block") == "pair") first_in_table = table.value(r, "first");
  }
  for (const json& row : by_hand.at("preference_scale")) {
    CHECK((row.at("interval") == "reference") == (row.at("variant") == first_in_table));
  }
  CHECK(by_hand.at("preference_fit").at("notes").back() ==
        "no variant parameter files: the trials table has no first_parameters or "
        "second_parameters column");
  const DoorModel tuned = doorbench::campaign_tobe_model(
      doorbench::study::read_campaign_for_spec(dir / "by-hand"), asis, source);
  CHECK(source ==
        "the centre of the panel's 2 tuned doors (tuning section; 17 sensory parameters "
        "on the reference sensory door), because the favourite variant " +
            favourite_of(by_hand) + " names no parameter file");
  REQUIRE(tuned_files.size() == 2);
  for (const char* name : {"J", "k_inf", "k_lock", "c"}) {
    double log_sum = 0;
    for (const std::string& file : tuned_files) {
      const DoorModel door = doorbench::load_model(doorbench::ModelKind::kSensory,
                                                   dir / "campaign" / "folder" / file, "");
      log_sum += std::log(door.parameter_values()[*door.find_parameter(name)]);
    }
    INFO(name);
    CHECK_THAT(tuned.parameter_values()[*tuned.find_parameter(name)],
               WithinRel(std::exp(log_sum / tuned_files.size()), 1e-9));
  }
}

// `spec --campaign` on the demo's simulated campaign writes the
// perceptual tolerance table, and its numbers agree with a direct Monte Carlo.
TEST_CASE(
    "the demo's campaign through analyze and spec --campaign: the perceptual table "
    "against a direct Monte Carlo",
    "[campaign][spec][slow]") {
  TempDir dir("campaign_chain_spec");
  demo_campaign_analysed(dir);
  const json analysis = read_json(dir / "analysis" / "analysis.json");
  const auto asis = dir.write(
      "physical-params.json",
      doorbench::to_parameter_json(doorbench::reference_model(doorbench::ModelKind::kPhysical)));
  const auto run =
      run_doorbench_shell("spec --campaign '" + (dir / "analysis").string() + "' --asis '" +
                              asis.string() + "' --out '" + (dir / "spec").string() +
                              "' --samples 200 --starts 1 --no-pdf --felt-share 5%",
                          dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  const std::string favourite = favourite_of(analysis);
  CHECK_THAT(run.err, Contains("TO-BE feel from the panel: the panel's favourite variant " +
                               favourite + " (largest worth on the preference scale)"));
  CHECK_THAT(run.out, Contains("tolerances judged by the panel:\n"));
  const json spec = read_json(dir / "spec" / "spec.json");
  const json& p = spec.at("perceptual");
  CHECK_THAT(p.at("tobe_source").get<std::string>(),
             StartsWith("the panel's favourite variant " + favourite));
  CHECK(p.at("felt_share") == 0.05);

  // The JNDs: the table's against the rule applied here to analysis.json.
  const std::map<std::string, double> jnds = expected_jnds(analysis);
  REQUIRE(p.at("quantities").size() == doorbench::kFeltQuantities.size());
  for (const json& q : p.at("quantities")) {
    INFO(q.dump());
    CHECK(q.at("weber_fraction").get<double>() == jnds.at(q.at("quantity").get<std::string>()));
  }
  CHECK(p.at("quantities").at(0).at("jnd_source") ==
        "measured: latch_effort (panel, psychometric fit, pooled)");

  // The design the spec wrote, its nominal felt quantities, and the direct Monte Carlo at the
  // tolerances as given and as proposed.
  const DoorModel design =
      doorbench::load_model(doorbench::ModelKind::kPhysical, dir / "spec" / "tobe-params.json", "");
  const doorbench::FeltQuantities nominal = doorbench::felt_quantities(design);
  const DirectShares given =
      direct_monte_carlo(design, spec.at("tolerances").at("parameters"), jnds, 600, 2029);
  const DirectShares proposed =
      direct_monte_carlo(design, p.at("proposal").at("tolerances"), jnds, 300, 2030);
  int informative = 0;
  for (std::size_t q = 0; q < doorbench::kFeltQuantities.size(); ++q) {
    const auto& info = doorbench::kFeltQuantities[q];
    const std::string name(info.name);
    const json& row = p.at("quantities").at(q);
    REQUIRE(row.at("quantity") == name);
    CHECK_THAT(row.at("nominal").get<double>(), WithinRel(nominal.*info.member, 1e-6));
    REQUIRE(given.doors.at(name) > 550);
    check_against_direct(row.at("as_given"), given.doors.at(name),
                         given.over.count(name) ? given.over.at(name) : 0, name + " as given");
    check_against_direct(row.at("proposed"), proposed.doors.at(name),
                         proposed.over.count(name) ? proposed.over.at(name) : 0,
                         name + " proposed");
    const double share = row.at("as_given").at("share").get<double>();
    if (share > 0.05 && share < 0.95) ++informative;
    if (p.at("proposal").at("reached").get<bool>()) {
      CHECK(row.at("proposed").at("share").get<double>() <= 0.05);
    }
  }
  CHECK(informative >= 1);  // some share is neither near 0 nor near 1: the check can fail
  CHECK(p.at("proposal").at("reached").get<bool>());
  const std::string html = doorbench::read_text_file(dir / "spec" / "spec.html");
  CHECK_THAT(html, Contains("Tolerances judged by the panel's perception"));
  CHECK_THAT(html, Contains("The panel's preference scale"));
  CHECK_THAT(html, Contains("Thresholds measured (panel)"));
}

// `spec --campaign` on the demo's campaign ends with every felt quantity
// of the design within its JND of the favourite's (read along the TO-BE strokes' motion, the
// JNDs the perceptual table uses), or with a warning naming each one that is not, by how much,
// the parts the search tried and how far the fit with every part free stays from it. The criterion
// is applied here to spec.json's numbers.
TEST_CASE(
    "spec --campaign: the design feels like the favourite, or a warning names each felt "
    "quantity that misses its JND",
    "[campaign][spec][slow]") {
  TempDir dir("campaign_chain_feel");
  demo_campaign_analysed(dir);
  const auto asis = dir.write(
      "physical-params.json",
      doorbench::to_parameter_json(doorbench::reference_model(doorbench::ModelKind::kPhysical)));
  const auto run = run_doorbench_shell(
      "spec --campaign '" + (dir / "analysis").string() + "' --asis '" + asis.string() +
          "' --out '" + (dir / "spec").string() + "' --samples 50 --starts 1 --no-pdf",
      dir);
  INFO("stdout: " << run.out << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  const json spec = read_json(dir / "spec" / "spec.json");
  const json& search = spec.at("design_search");
  CHECK(search.at("goal") == "every felt quantity within its JND");
  const json& errors = spec.at("check").at("after").at("errors");
  const json& quantities = spec.at("perceptual").at("quantities");
  REQUIRE(errors.size() == doorbench::kFeltQuantities.size());
  int missed = 0;
  for (std::size_t q = 0; q < doorbench::kFeltQuantities.size(); ++q) {
    const auto& info = doorbench::kFeltQuantities[q];
    REQUIRE(errors.at(q).at("name") == std::string(info.name));
    REQUIRE(quantities.at(q).at("quantity") == std::string(info.name));
    if (errors.at(q).at("model").is_null() || errors.at(q).at("recorded").is_null()) continue;
    const double design = errors.at(q).at("model").get<double>();
    const double tobe = errors.at(q).at("recorded").get<double>();
    const double w = quantities.at(q).at("weber_fraction").get<double>();
    if (tobe == 0.0) continue;
    const bool different =
        !(design / tobe > 0) || std::abs(std::log(design / tobe)) > std::log1p(w);
    INFO(info.name << ": design " << design << ", TO-BE " << tobe << ", JND " << w);
    bool warned = false;
    for (const json& warning : spec.at("warnings")) {
      const std::string text = warning.get<std::string>();
      if (text.find("its " + doorbench::felt_label(info) + " is ") == std::string::npos) continue;
      warned = true;
      CHECK_THAT(text, Contains("the sparse search tried "));
      // How far the fit with every part free stays in the same quantity.
      CHECK_THAT(text, Contains("; with every part free ("));
      CHECK_THAT(text, StartsWith("the design does not feel like the TO-BE: "));
    }
    CHECK(warned == different);
    if (different) {
      ++missed;
      CHECK_THAT(run.err, Contains("warning: the design does not feel like the TO-BE: its " +
                                   doorbench::felt_label(info)));
    }
  }
  CHECK(search.at("felt_misses").size() == static_cast<std::size_t>(missed));
  if (missed > 0) {
    const json& every_part = search.at("every_part_free");
    REQUIRE(every_part.is_object());
    CHECK(every_part.at("parts_changed").get<int>() > 0);
    for (const json& miss : every_part.at("felt_misses")) {
      if (miss.at("jnds").is_number()) CHECK(miss.at("jnds").get<double>() > 1.0);
    }
  }
  if (missed == 0) {
    CHECK_THAT(search.at("stopped").get<std::string>(),
               Contains("every felt quantity is within its JND of the TO-BE's"));
  }
}

TEST_CASE("demo campaign: a second run replaces the earlier demo's, another folder is refused",
          "[campaign][outputs]") {
  const TempDir dir("demo_campaign_again");
  std::ostringstream first, second;
  doorbench::app::run_demo_campaign(dir / "campaign", first);
  const auto rows_first =
      doorbench::study::read_trials_table(dir / "campaign" / "folder" / "trials.csv").rows.size();
  CHECK_THAT(first.str(), !Contains("replaced"));
  doorbench::app::run_demo_campaign(dir / "campaign", second);
  const auto rows_second =
      doorbench::study::read_trials_table(dir / "campaign" / "folder" / "trials.csv").rows.size();
  CHECK(rows_second == rows_first);
  CHECK_THAT(second.str(), Contains("/trials.csv (an earlier demo's campaign there replaced)\n"));

  // A folder that is not a demo campaign's stays as it is.
  const TempDir other("demo_campaign_other");
  other.write("campaign/folder/notes.txt", "the user's\n");
  std::ostringstream refused;
  CHECK_THROWS_WITH(doorbench::app::run_demo_campaign(other / "campaign", refused),
                    (other / "campaign" / "folder").string() +
                        ": exists and is not empty (give --overwrite to write into it)");
  CHECK(std::filesystem::exists(other / "campaign" / "folder" / "notes.txt"));
}
