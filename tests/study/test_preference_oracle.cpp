// The preference scale against independent implementations in R: BradleyTerry2's BTm for
// Bradley–Terry with and without the first-position advantage, and R's glm on the Poisson
// log-linear form of Davidson's tie model with the order effect (tests/study/preference_oracle.R).
// The data sets are simulated with a known truth; the point estimates must agree to 1e-4 relative,
// and the worths' quasi-variances (Firth & de Menezes 2004) with R's qvcalc (of BTabilities
// for BTm, of the worths' covariance block for glm) to 1e-6 relative.
// R, r-cran-bradleyterry2 and r-cran-qvcalc come from scripts/install-deps.sh; without them
// this test fails.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "fixtures/temp_dir.h"
#include "study/statistics/preference_scale.h"
#include "tests/study/simulated_panel.h"
#include "tests/support/files.h"

using doorbench::study::fit_preference_scale;
using doorbench::study::pair_data;
using doorbench::study::PreferenceOptions;
using doorbench::study::PreferenceScale;
using doorbench::study::read_trials_table;
using doorbench::testing::kTrialsHeader;
using doorbench::testing::PairPanel;
using doorbench::testing::read_file;
using doorbench::testing::simulate_pairs;
using doorbench::testing::TempDir;

namespace {

// Runs the R script in `mode` on the table; its "NAME VALUE" lines.
std::map<std::string, double> r_estimates(const std::string& mode,
                                          const std::filesystem::path& table, const TempDir& dir) {
  REQUIRE(std::system("command -v Rscript > /dev/null 2>&1") == 0);  // install-deps.sh
  const auto out = dir / (mode + ".txt");
  const auto err = dir / (mode + ".err");
  const std::string command =
      "Rscript '" DOORBENCH_SOURCE_DIR "/tests/study/preference_oracle.R' " + mode + " '" +
      table.string() + "' > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  INFO(read_file(err));
  REQUIRE(status == 0);
  std::map<std::string, double> values;
  std::istringstream lines(read_file(out));
  std::string name;
  double value = 0;
  while (lines >> name >> value) values[name] = value;
  return values;
}

PreferenceScale doorbench_estimates(const std::filesystem::path& table, bool order) {
  PreferenceOptions options;
  options.bootstrap_replicates = 0;
  options.order_effect = order;
  return fit_preference_scale(pair_data(read_trials_table(table)), options);
}

void compare_worths(const PreferenceScale& scale, const std::map<std::string, double>& r) {
  REQUIRE(r.size() >= scale.worths.size() - 1);
  CHECK(scale.worths[0].worth.value == 0);
  for (std::size_t v = 1; v < scale.worths.size(); ++v) {
    const std::string& name = scale.worths[v].variant;
    INFO("variant " << name);
    REQUIRE(r.count(name) == 1);
    CHECK(scale.worths[v].worth.value == Approx(r.at(name)).epsilon(1e-4));
  }
  // Every variant's quasi-variance, the reference's included.
  for (const auto& w : scale.worths) {
    INFO("quasi-variance of " << w.variant);
    REQUIRE(r.count("qv_" + w.variant) == 1);
    CHECK(w.quasi_variance == Approx(r.at("qv_" + w.variant)).epsilon(1e-6));
  }
  CHECK(scale.quasi_variance_error < 0.1);
}

std::filesystem::path write_table(const TempDir& dir, const std::string& name,
                                  const PairPanel& panel, std::uint64_t seed) {
  const auto path = dir / name;
  std::ofstream(path) << kTrialsHeader << simulate_pairs(panel, seed);
  return path;
}

}  // namespace

TEST_CASE(
    "ties: Davidson worths, order effect and nu agree with R's glm to 1e-4, quasi-variances "
    "with qvcalc to 1e-6",
    "[study]") {
  TempDir dir("oracle_ties");
  PairPanel panel;
  panel.nu = 0.6;
  panel.delta = 0.3;
  panel.participants = 15;
  panel.repetitions = 3;
  const auto table = write_table(dir, "ties.csv", panel, 101);
  const auto scale = doorbench_estimates(table, true);
  const auto r = r_estimates("davidson", table, dir);
  compare_worths(scale, r);
  REQUIRE(scale.order);
  CHECK(scale.order->value == Approx(r.at("delta")).epsilon(1e-4));
  REQUIRE(scale.nu);
  CHECK(std::log(scale.nu->value) == Approx(r.at("log_nu")).epsilon(1e-4));
}

TEST_CASE(
    "order effect: worths and the first-position advantage agree with BTm to 1e-4, "
    "quasi-variances with qvcalc to 1e-6",
    "[study]") {
  TempDir dir("oracle_order");
  PairPanel panel;
  panel.delta = 0.5;
  panel.participants = 12;
  panel.repetitions = 2;
  const auto table = write_table(dir, "order.csv", panel, 202);
  const auto scale = doorbench_estimates(table, true);
  const auto r = r_estimates("btm-order", table, dir);
  compare_worths(scale, r);
  REQUIRE(scale.order);
  CHECK(scale.order->value == Approx(r.at("delta")).epsilon(1e-4));
}

TEST_CASE(
    "20 participants who differ: worths agree with BTm to 1e-4, quasi-variances with "
    "qvcalc to 1e-6",
    "[study]") {
  TempDir dir("oracle_panel");
  PairPanel panel;
  panel.variants = {"ref", "heavier", "easier", "smooth", "stiff"};
  panel.worths = {0.0, 0.4, 0.8, -0.2, 0.1};
  panel.heterogeneity_sd = 0.5;
  panel.participants = 20;
  panel.repetitions = 1;
  const auto table = write_table(dir, "panel.csv", panel, 303);
  const auto scale = doorbench_estimates(table, false);
  CHECK(scale.participants == 20);
  compare_worths(scale, r_estimates("btm", table, dir));
}
