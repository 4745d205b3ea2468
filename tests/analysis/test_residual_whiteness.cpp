// Residual whiteness: the autocorrelation of a white residual stays in the
// 99 % band, an AR(1) residual's does not, and a residual that follows the force three
// samples later shows at cross-correlation lag +3; strokes are never bridged.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "analysis/fit/residual_whiteness.h"

using namespace doorbench;

namespace {

// Four strokes of 1500 samples of white noise (seeded).
std::vector<std::vector<double>> white(unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<std::vector<double>> strokes(4, std::vector<double>(1500));
  for (auto& stroke : strokes) {
    for (double& v : stroke) v = normal(random);
  }
  return strokes;
}

}  // namespace

TEST_CASE("residual whiteness: white noise inside the band, coloured residuals outside",
          "[fit][whiteness]") {
  const auto force = white(1);
  const auto noise = white(2);
  const ResidualWhiteness w = residual_whiteness(noise, force, 0.001, 50);
  REQUIRE(w.samples == 6000);
  CHECK(w.band == Approx(2.576 / std::sqrt(6000.0)));
  CHECK(w.autocorrelation[0] == Approx(1.0));
  CHECK(w.auto_outside <= 3);   // 1 % of 50 lags expected
  CHECK(w.cross_outside <= 4);  // of 101
  CHECK(w.summary().rfind("residual autocorrelation: ", 0) == 0);
  CHECK_THAT(w.report_line(), Catch::EndsWith("; verdict: white: consistent with noise"));

  // AR(1) with 0.8: r(1) near 0.8 and many lags outside.
  auto coloured = noise;
  for (auto& stroke : coloured) {
    for (std::size_t i = 1; i < stroke.size(); ++i) stroke[i] += 0.8 * stroke[i - 1];
  }
  const ResidualWhiteness ar = residual_whiteness(coloured, force, 0.001, 50);
  CHECK(ar.autocorrelation[1] == Approx(0.8).margin(0.03));
  CHECK(ar.auto_outside >= 10);
  CHECK_THAT(ar.report_line(),
             Catch::EndsWith("; verdict: not white: correlated in time but not with the force "
                             "(coloured noise such as the rate's filtering, or dynamics the force "
                             "does not drive)"));

  // The residual follows the force 3 samples later: the cross-correlation peaks at +3.
  auto following = noise;
  for (std::size_t s = 0; s < following.size(); ++s) {
    for (std::size_t i = 3; i < following[s].size(); ++i) following[s][i] += force[s][i - 3];
  }
  const ResidualWhiteness x = residual_whiteness(following, force, 0.001, 50);
  const double at_3 = x.cross_correlation[50 + 3];
  CHECK(at_3 > 0.6);
  CHECK(std::abs(x.cross_correlation[50 - 3]) < x.band * 1.5);
  CHECK(x.cross_outside >= 1);
  // One clear peak is enough for the verdict, however few lags are outside.
  CHECK_THAT(x.report_line(),
             Catch::Contains("(largest |r| 0.7") &&
                 Catch::Contains(" at lag 0.003 s); verdict: not white: the residual follows "
                                 "the force (dynamics the model does not reproduce, whatever the "
                                 "residual's size)"));
}

TEST_CASE("residual whiteness: lags stay inside each stroke, and bad input is refused",
          "[fit][whiteness]") {
  // Two strokes, each an alternating +1/-1 run: within a stroke r(1) = -1 exactly; a lag
  // bridging the strokes would add a product across their boundary.
  std::vector<std::vector<double>> r = {{1, -1, 1, -1, 1, -1}, {1, -1, 1, -1, 1, -1}};
  const ResidualWhiteness w =
      residual_whiteness(r, {{1, 2, 3, 1, 2, 3}, {3, 1, 2, 3, 1, 2}}, 0.01, 2);
  CHECK(w.autocorrelation[1] == Approx(-10.0 / 12.0));  // 5 products per stroke of 6 samples
  CHECK_THROWS_WITH(residual_whiteness(r, {{1}}, 0.01, 2),
                    "residual whiteness: 2 residual strokes but 1 force strokes");
  CHECK_THROWS_WITH(residual_whiteness({{1, 2}}, {{1}}, 0.01, 2),
                    "residual whiteness: stroke 0 has 2 residuals but 1 forces");
  CHECK_THROWS_WITH(residual_whiteness(r, r, 0.01, 0), "residual whiteness: max_lag must be >= 1");
  CHECK_THROWS_WITH(residual_whiteness(r, r, 0.01, 7),
                    "residual whiteness: 12 finite samples (not constant) needed at least 14");
}

TEST_CASE("residual whiteness: the report line, word for word", "[fit][whiteness]") {
  ResidualWhiteness w;
  w.lag_step_s = 0.01;
  w.samples = 700;
  w.band = 0.1;
  w.autocorrelation = {1.0, 0.05, -0.02, 0.03};
  w.cross_correlation = {0.01, -0.04, 0.05, 0.02, 0.0};  // lags -2 … 2
  CHECK(w.report_line() ==
        "residual whiteness: autocorrelation outside the 99 % band (±0.1) at 0 of 3 lags "
        "(largest |r| 0.05 at lag 0.01 s); cross-correlation with the force outside it at 0 of "
        "5 lags (largest |r| 0.05 at lag 0 s); verdict: white: consistent with noise");
  // A peak above twice the band at lag +2 (the force leading): the force is named.
  w.cross_correlation[4] = -0.25;
  w.cross_outside = 1;
  CHECK(w.report_line() ==
        "residual whiteness: autocorrelation outside the 99 % band (±0.1) at 0 of 3 lags "
        "(largest |r| 0.05 at lag 0.01 s); cross-correlation with the force outside it at 1 of "
        "5 lags (largest |r| 0.25 at lag 0.02 s); verdict: not white: the residual follows the "
        "force (dynamics the model does not reproduce, whatever the residual's size)");
  // The autocorrelation alone: 1 of 3 lags outside is more than 5 % of them.
  w.cross_correlation[4] = 0.0;
  w.cross_outside = 0;
  w.autocorrelation[2] = 0.15;
  w.auto_outside = 1;
  CHECK(w.report_line() ==
        "residual whiteness: autocorrelation outside the 99 % band (±0.1) at 1 of 3 lags "
        "(largest |r| 0.15 at lag 0.02 s); cross-correlation with the force outside it at 0 of "
        "5 lags (largest |r| 0.05 at lag 0 s); verdict: not white: correlated in time but not "
        "with the force (coloured noise such as the rate's filtering, or dynamics the force does "
        "not drive)");
}
