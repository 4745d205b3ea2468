// The equivalence verdicts of identify-real (2-AFC) and 2-AC against a hand computation in R
// (tests/study/r/equivalence.R: binom.test and pbinom for 2-AFC; the 2-AC likelihood, its
// profile by optimize and its limits by uniroot): the 95 % interval of d', the test of no
// difference, the two one-sided tests' p-value against ±1 and which verdict the data give.
// R comes from scripts/install-deps.sh (r-base-core); without it this test fails.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>

#include "fixtures/temp_dir.h"
#include "study/statistics/discrimination.h"
#include "tests/support/files.h"

using doorbench::study::Conclusion;
using doorbench::testing::read_file;
using doorbench::testing::TempDir;

namespace {

// "NAME VALUE" lines of equivalence.R for `arguments`; R writes infinities as Inf.
std::map<std::string, double> r_equivalence(const std::string& arguments, const TempDir& dir) {
  REQUIRE(std::system("command -v Rscript > /dev/null 2>&1") == 0);  // install-deps.sh
  const auto out = dir / "r.txt";
  const auto err = dir / "r.err";
  const std::string command = "Rscript '" DOORBENCH_SOURCE_DIR "/tests/study/r/equivalence.R' " +
                              arguments + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  INFO(read_file(err));
  REQUIRE(status == 0);
  std::map<std::string, double> values;
  std::istringstream lines(read_file(out));
  std::string name, value;
  while (lines >> name >> value) values[name] = std::strtod(value.c_str(), nullptr);
  return values;
}

// R's verdict numbers: 1 different, 2 equivalent, 3 neither, 4 different within the margin.
int verdict_number(Conclusion conclusion) {
  switch (conclusion) {
    case Conclusion::kDifferent:
      return 1;
    case Conclusion::kEquivalent:
      return 2;
    case Conclusion::kInconclusive:
      return 3;
    case Conclusion::kDifferentWithinMargin:
      return 4;
  }
  return 0;
}

void check_end(double doorbench, double r, double tolerance) {
  if (std::isinf(r)) {
    CHECK(doorbench == r);
  } else {
    CHECK(doorbench == Approx(r).epsilon(tolerance).margin(tolerance));
  }
}

}  // namespace

TEST_CASE("identify-real's interval, tests and verdict agree with a hand computation in R",
          "[study]") {
  TempDir dir("equivalence_2afc");
  const std::pair<int, int> counts[] = {{7, 10}, {160, 300}, {60, 80}, {5300, 10000}, {20, 80},
                                        {9, 16}, {12, 12},   {0, 12},  {530, 1000}};
  for (const auto& [correct, n] : counts) {
    INFO(correct << " of " << n);
    const auto r =
        r_equivalence("2afc " + std::to_string(correct) + " " + std::to_string(n) + " 1", dir);
    doorbench::study::IdentifyReal result;
    result.panel = doorbench::study::forced_choice_2afc(correct, n, 0.95, 1.0);
    result = doorbench::study::identify_verdict(result, 0.95);
    check_end(result.panel.ci_low, r.at("ci_low"), 1e-9);
    check_end(result.panel.ci_high, r.at("ci_high"), 1e-9);
    CHECK(result.panel.p == Approx(r.at("p")).epsilon(1e-9));
    CHECK(result.panel.p_equivalence == Approx(r.at("p_tost")).epsilon(1e-9).margin(1e-300));
    CHECK(verdict_number(result.conclusion) == int(r.at("verdict")));
  }
}

TEST_CASE("2-AC's interval, tests and verdict agree with a hand computation in R", "[study]") {
  TempDir dir("equivalence_2ac");
  const char* counts[] = {"2 2 6",  "60 300 80", "5 5 30",   "0 3 9", "7 0 0",
                          "12 5 7", "20 3 1",    "30 40 28", "0 2 2"};
  for (const char* text : counts) {
    INFO(text);
    const auto r = r_equivalence(std::string("2ac ") + text + " 1", dir);
    int n1 = 0, n2 = 0, n3 = 0;
    std::istringstream(text) >> n1 >> n2 >> n3;
    const auto result = doorbench::study::two_ac(n1, n2, n3, 0.95, 1.0);
    check_end(result.dprime, r.at("dprime"), 1e-9);
    check_end(result.ci_low, r.at("ci_low"), 1e-6);
    check_end(result.ci_high, r.at("ci_high"), 1e-6);
    CHECK(result.p == Approx(r.at("p")).epsilon(1e-5).margin(1e-12));
    CHECK(result.p_equivalence == Approx(r.at("p_tost")).epsilon(1e-5).margin(1e-12));
    CHECK(verdict_number(result.conclusion) == int(r.at("verdict")));
  }
}
