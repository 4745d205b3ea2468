// The Student-t quantile behind the calibrations' expanded uncertainties
// (calibration/least_squares.h), against closed forms and published values.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "calibration/least_squares.h"

using Catch::Matchers::Equals;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::calibration::small_sample_factor;
using doorbench::calibration::student_t_95;

TEST_CASE("Student-t 95 %: closed forms for 1 and 2 degrees of freedom", "[least_squares]") {
  // ν = 1 (Cauchy): tan(π (0.975 − 1/2)); ν = 2: (2p − 1) √(2 / (4 p (1 − p))), p = 0.975.
  CHECK_THAT(student_t_95(1), WithinRel(std::tan(0.475 * std::numbers::pi), 1e-12));
  CHECK_THAT(student_t_95(2), WithinRel(0.95 * std::sqrt(2.0 / 0.0975), 1e-12));
}

TEST_CASE("Student-t 95 %: published table values", "[least_squares]") {
  // t(0.975, ν) to six decimals (e.g. R's qt(0.975, ν), NIST/SEMATECH table 1.3.6.7.2).
  CHECK_THAT(student_t_95(3), WithinAbs(3.182446, 1e-6));
  CHECK_THAT(student_t_95(4), WithinAbs(2.776445, 1e-6));
  CHECK_THAT(student_t_95(5), WithinAbs(2.570582, 1e-6));
  CHECK_THAT(student_t_95(10), WithinAbs(2.228139, 1e-6));
  CHECK_THAT(student_t_95(30), WithinAbs(2.042272, 1e-6));
  CHECK_THAT(student_t_95(120), WithinAbs(1.979930, 1e-6));
  // The normal limit: z(0.975) = 1.959964.
  CHECK_THAT(student_t_95(1'000'000'000), WithinAbs(1.959964, 1e-6));
  CHECK_THROWS_WITH(student_t_95(0), Equals("student_t_95: needs >= 1 degree of freedom"));
}

TEST_CASE("Small-sample factor: t over z, never below 1", "[least_squares]") {
  CHECK_THAT(small_sample_factor(1), WithinRel(6.482876642836103, 1e-12));
  CHECK_THAT(small_sample_factor(10), WithinAbs(2.228139 / 1.959964, 1e-6));
  for (const int nu : {1, 2, 5, 100, 10'000, 1'000'000, 2'147'483'647}) {
    INFO("nu = " << nu);
    CHECK(small_sample_factor(nu) >= 1.0);
  }
}
