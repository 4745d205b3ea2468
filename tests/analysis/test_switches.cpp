// The smooth switches of door-models.md §1 and the cam's softplus/softmin of §3.1,
// checked against the spec's definitions with values worked out by hand.
#include <ceres/jet.h>

#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/model/switches.h"

using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::logistic;
using doorbench::softmin;
using doorbench::softplus;
using doorbench::switch_off;
using doorbench::switch_on;
using doorbench::window;

namespace {
// ½ (1 + tanh 2) and ½ (1 − tanh 2), tanh 2 = 0.964027580075817.
constexpr double kHalfOnePlusTanh2 = 0.98201379003790845;
constexpr double kHalfOneMinusTanh2 = 0.01798620996209156;
}  // namespace

TEST_CASE("S is one half at its midpoint and S-bar is its complement", "[switches]") {
  for (double beta : {10.0, 3000.0, 20000.0}) {
    for (double x0 : {-0.3, 0.0, 0.02793, 1.2}) {
      CHECK(switch_on(x0, x0, beta) == 0.5);
      CHECK(switch_off(x0, x0, beta) == 0.5);
      for (double dx : {-3.0 / beta, -0.5 / beta, 0.25 / beta, 2.0 / beta}) {
        CHECK_THAT(switch_on(x0 + dx, x0, beta) + switch_off(x0 + dx, x0, beta),
                   WithinAbs(1.0, 1e-15));
      }
    }
  }
}

TEST_CASE("S is about 0 far below and about 1 far above its midpoint", "[switches]") {
  // β (x − x0) = ±30: ½ (1 − tanh 30) = e^−60 / (1 + e^−60) ≈ 9e−27.
  const double beta = 3000.0, x0 = 0.02;
  CHECK_THAT(switch_on(x0 - 0.01, x0, beta), WithinAbs(0.0, 1e-12));
  CHECK_THAT(switch_on(x0 + 0.01, x0, beta), WithinAbs(1.0, 1e-12));
  CHECK_THAT(switch_off(x0 - 0.01, x0, beta), WithinAbs(1.0, 1e-12));
  CHECK_THAT(switch_off(x0 + 0.01, x0, beta), WithinAbs(0.0, 1e-12));
  // Very far away (β Δx = ±3e6): saturates, no NaN.
  CHECK(switch_on(-1000.0, x0, beta) == 0.0);
  CHECK(switch_on(1000.0, x0, beta) == 1.0);
  // Monotone increasing.
  double previous = -1.0;
  for (int i = -50; i <= 50; ++i) {
    const double s = switch_on(x0 + i * 1e-4, x0, beta);
    CHECK(s >= previous);
    previous = s;
  }
}

TEST_CASE("The transition of S is about 4/beta wide", "[switches]") {
  for (double beta : {10.0, 3000.0}) {
    const double x0 = 0.5;
    // S(x0 ± 2/β) = ½ (1 ± tanh 2): from 1.8% to 98.2% over 4/β.
    CHECK_THAT(switch_on(x0 + 2.0 / beta, x0, beta), WithinRel(kHalfOnePlusTanh2, 1e-12));
    CHECK_THAT(switch_on(x0 - 2.0 / beta, x0, beta), WithinRel(kHalfOneMinusTanh2, 1e-10));
    CHECK_THAT(switch_off(x0 + 2.0 / beta, x0, beta), WithinRel(kHalfOneMinusTanh2, 1e-10));
    // S(x0 + 1/β) = ½ (1 + tanh 1) = 0.8807970779778823.
    CHECK_THAT(switch_on(x0 + 1.0 / beta, x0, beta), WithinRel(0.8807970779778823, 1e-12));
  }
}

TEST_CASE("W is about 1 inside its window and about 0 outside", "[switches]") {
  // The reference door's snap zone: θ1 = 0.02793 to θ2 = 0.0384, β = 3000.
  const double a = 0.02793, b = 0.0384, beta = 3000.0;
  // Middle: both edges 15.7 switch widths away, W = 1 − O(e^−31).
  CHECK_THAT(window(0.5 * (a + b), a, b, beta), WithinAbs(1.0, 1e-12));
  // Outside by 0.01 rad (β Δ = 30): W = O(e^−60).
  CHECK_THAT(window(a - 0.01, a, b, beta), WithinAbs(0.0, 1e-12));
  CHECK_THAT(window(b + 0.01, a, b, beta), WithinAbs(0.0, 1e-12));
  // On an edge: ½ minus the other edge's contribution (≈ 0): W(a) = ½.
  CHECK_THAT(window(a, a, b, beta), WithinAbs(0.5, 1e-12));
  CHECK_THAT(window(b, a, b, beta), WithinAbs(0.5, 1e-12));
  // Two widths inside the lower edge: ½ (1 + tanh 2).
  CHECK_THAT(window(a + 2.0 / beta, a, b, beta), WithinRel(kHalfOnePlusTanh2, 1e-10));
}

TEST_CASE("logistic is 1 / (1 + exp(-u)) and never overflows", "[switches]") {
  CHECK(logistic(0.0) == 0.5);
  for (double u : {-5.0, -1.0, 0.3, 2.0, 17.0, 30.0}) {
    CHECK_THAT(logistic(u), WithinRel(1.0 / (1.0 + std::exp(-u)), 1e-13));
  }
  // Far left the tanh form keeps its absolute (not relative) accuracy: e^−30 ≈ 9.36e−14.
  CHECK_THAT(logistic(-30.0), WithinAbs(9.357622968840175e-14, 1e-16));
  // 1 / (1 + e) = 0.2689414213699951.
  CHECK_THAT(logistic(-1.0), WithinRel(0.2689414213699951, 1e-14));
  // exp(800) overflows; the limits are 0 and 1.
  CHECK(logistic(-800.0) == 0.0);
  CHECK(logistic(800.0) == 1.0);
}

TEST_CASE("softplus matches e ln(1 + exp(z/e)) and its asymptotes", "[switches]") {
  const double e = 0.0003;
  // softplus_e(0) = e ln 2.
  CHECK_THAT(softplus(0.0, e), WithinRel(e * 0.6931471805599453, 1e-14));
  // Where exp(z/e) is representable (and 1 + exp(z/e) does not round away its
  // information), the naive formula.
  for (double ratio : {-5.0, -3.0, -0.5, 0.1, 1.0, 4.0, 30.0}) {
    const double z = ratio * e;
    const double naive = e * std::log(1.0 + std::exp(z / e));
    CHECK_THAT(softplus(z, e), WithinRel(naive, 1e-12));
  }
  // z/e = −30: e ln(1 + e^−30) = e (e^−30 − e^−60/2 ...) ≈ 0.0003 · 9.357622968840175e−14.
  CHECK_THAT(softplus(-30.0 * e, e), WithinRel(e * 9.357622968840175e-14, 1e-12));
  // ratio = 1: e ln(1 + e¹) = e · 1.3132616875182228.
  CHECK_THAT(softplus(e, e), WithinRel(e * 1.3132616875182228, 1e-13));
  // Far above: naive exp(z/e) = exp(1e4) overflows; softplus → z.
  CHECK(std::isinf(std::exp(3.0 / e)));
  CHECK_THAT(softplus(3.0, e), WithinRel(3.0, 1e-15));
  CHECK_THAT(softplus(0.05, e), WithinRel(0.05, 1e-15));  // z/e = 166.7
  // Far below: → e exp(z/e) → 0, never negative.
  const double far_below = softplus(-0.05, e);
  CHECK(far_below >= 0.0);
  CHECK(far_below < 1e-70);  // e · e^−166.7 ≈ 8.7e−77
  CHECK(softplus(-3.0, e) == 0.0);
  CHECK(softplus(-1e300, e) == 0.0);
  CHECK(softplus(1e300, e) == 1e300);
}

TEST_CASE("softmin matches -e ln(exp(-a/e) + exp(-b/e)) and its asymptotes", "[switches]") {
  const double e = 0.0003;
  // a = b: −e ln(2 exp(−a/e)) = a − e ln 2.
  CHECK_THAT(softmin(0.002, 0.002, e), WithinRel(0.002 - e * 0.6931471805599453, 1e-13));
  // Where the exponentials are representable, the naive formula.
  for (auto [a, b] : {std::pair{0.001, 0.0012}, std::pair{0.003, 0.0001}, std::pair{-0.001, 0.002},
                      std::pair{0.004, 0.004 + 3 * e}}) {
    const double naive = -e * std::log(std::exp(-a / e) + std::exp(-b / e));
    CHECK_THAT(softmin(a, b, e), WithinRel(naive, 1e-12));
    CHECK(softmin(a, b, e) == softmin(b, a, e));  // symmetric
    CHECK(softmin(a, b, e) <= std::min(a, b));    // never above the minimum
  }
  // a = 0.001, b = 0.0013 (one e apart): min − e ln(1 + e^−1) = 0.001 − 0.0003 · 0.31326168751822.
  CHECK_THAT(softmin(0.001, 0.0013, e), WithinRel(0.001 - e * 0.3132616875182228, 1e-12));
  // Far apart in units of e: naive exp(−a/e) underflows to 0 for both at a, b ≈ 1
  // (a/e ≈ 3333), giving ln 0; softmin → min(a, b).
  CHECK(std::exp(-1.0 / e) == 0.0);
  CHECK_THAT(softmin(1.0, 2.0, e), WithinRel(1.0, 1e-15));
  CHECK_THAT(softmin(2.0, 1.0, e), WithinRel(1.0, 1e-15));
  // Large negative arguments: naive exp(+a/e) overflows; softmin → min.
  CHECK_THAT(softmin(-1.0, 0.5, e), WithinRel(-1.0, 1e-15));
}

TEST_CASE("The switches' derivatives (through Ceres Jets) match the spec's", "[switches]") {
  using Jet = ceres::Jet<double, 1>;
  // dS/dx = (β/2) sech²(β (x − x0)): β/2 at the midpoint.
  const double beta = 3000.0, x0 = 0.02793;
  Jet s = switch_on(Jet(x0, 0), Jet(x0), Jet(beta));
  CHECK_THAT(s.v[0], WithinRel(1500.0, 1e-14));
  // one width 1/β above: (β/2) sech²(1) = 1500 · 0.41997434161402614.
  s = switch_on(Jet(x0 + 1.0 / beta, 0), Jet(x0), Jet(beta));
  CHECK_THAT(s.v[0], WithinRel(1500.0 * 0.41997434161402614, 1e-10));
  Jet sbar = switch_off(Jet(x0, 0), Jet(x0), Jet(beta));
  CHECK_THAT(sbar.v[0], WithinRel(-1500.0, 1e-14));
  // softplus′(z) = logistic(z/e): 1/(1+e^−1) at z = e, 1/(1+e) at z = −e.
  const double e = 0.0003;
  CHECK_THAT(softplus(Jet(e, 0), Jet(e)).v[0], WithinRel(0.7310585786300049, 1e-12));
  CHECK_THAT(softplus(Jet(-e, 0), Jet(e)).v[0], WithinRel(0.2689414213699951, 1e-12));
  // ∂/∂e [e ln(1 + exp(z/e))] at z = 0 is ln 2.
  CHECK_THAT(softplus(Jet(0.0), Jet(e, 0)).v[0], WithinRel(0.6931471805599453, 1e-12));
  // softmin: ∂/∂a = exp(−a/e) / (exp(−a/e) + exp(−b/e)) = logistic((b − a)/e).
  // a = 0.001, b = 0.0013: logistic(1) = 0.7310585786300049.
  const Jet m = softmin(Jet(0.001, 0), Jet(0.0013), Jet(e));
  CHECK_THAT(m.v[0], WithinRel(0.7310585786300049, 1e-12));
  // a = b: both weights ½, so d softmin(x, x)/dx = 1.
  CHECK_THAT(softmin(Jet(0.002, 0), Jet(0.002, 0), Jet(e)).v[0], WithinRel(1.0, 1e-14));
}

// softplus is smooth: its slope at z = 0 is logistic(0) = ½. The max(z, 0) + ... form
// takes max's branch 0 (slope 0) and |z|'s slope +1 at exactly z = 0, giving −½.
TEST_CASE("softplus' slope at exactly z = 0 is one half", "[switches]") {
  using Jet = ceres::Jet<double, 1>;
  const double e = 0.0003;
  CHECK_THAT(softplus(Jet(0.0, 0), Jet(e)).v[0], WithinRel(0.5, 1e-12));
}
