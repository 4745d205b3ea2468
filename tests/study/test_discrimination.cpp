#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "core/number_format.h"
#include "study/statistics/discrimination.h"

using doorbench::study::Conclusion;
using doorbench::study::forced_choice_2afc;
using doorbench::study::identify_real;
using doorbench::study::identify_verdict;
using doorbench::study::IdentifyReal;
using doorbench::study::parse_trials_table;
using doorbench::study::TrialsTableError;
using doorbench::study::two_ac;
using doorbench::study::two_ac_pairs;

namespace {
const std::string kHeader = "participant,block,trial,question,first,second,answer\n";
}

// The worked example of Christensen, Lee & Brockhoff (2012), as printed by sensR's twoAC
// (its R companion "Estimation of the Thurstonian model for the 2-AC protocol", example 1,
// and the stored values in sensR's clm2twoAC help page): counts (2, 2, 6) give
// tau 0.4160 (SE 0.2674), d' 0.7743 (SE 0.5417), likelihood interval [-0.271, 1.859],
// likelihood root statistic 1.446718, p 0.14798.
TEST_CASE("2-AC on the published worked example gives the published tau, d' and interval",
          "[study]") {
  const auto r = two_ac(2, 2, 6);
  CHECK(r.tau == Approx(0.415972626828703).epsilon(1e-10));
  CHECK(r.dprime == Approx(0.774259536071287).epsilon(1e-10));
  CHECK(r.se_tau == Approx(0.26743108470048).epsilon(1e-7));
  CHECK(r.se_dprime == Approx(0.541673720311043).epsilon(1e-7));
  CHECK(r.ci_low == Approx(-0.27098319957656).epsilon(1e-5));
  CHECK(r.ci_high == Approx(1.85925113345333).epsilon(1e-5));
  CHECK(r.p == Approx(0.147975959384948).epsilon(1e-5));
}

TEST_CASE("2-AC: swapping the variants flips d' and keeps tau", "[study]") {
  const auto ab = two_ac(7, 5, 12), ba = two_ac(12, 5, 7);
  CHECK(ab.dprime == Approx(-ba.dprime));
  CHECK(ab.tau == Approx(ba.tau));
  CHECK(ab.ci_low == Approx(-ba.ci_high).epsilon(1e-6));
  CHECK(ab.ci_high == Approx(-ba.ci_low).epsilon(1e-6));
}

// Nobody preferred A: d' is +infinity, the interval open above, its lower end where the
// profile falls from the likelihood's supremum (checked against R in
// test_equivalence_r_oracle.cpp); every answer "same": no d' at all.
TEST_CASE(
    "2-AC: a pair nobody preferred one way has an infinite d', a one-sided interval and says so",
    "[study]") {
  const auto r = two_ac(0, 3, 9);
  CHECK(std::isinf(r.dprime));
  CHECK(r.dprime > 0);
  CHECK(std::isinf(r.ci_high));
  CHECK(r.ci_low == Approx(0.921711904513188).epsilon(1e-6));
  CHECK(r.p == Approx(0.000412070679784436).epsilon(1e-5));
  CHECK(r.note == "nobody preferred A: d' is infinite and its interval open above");
  CHECK(r.verdict ==
        "B preferred to A: d' inf [0.92, inf], 0 prefer A, 3 same, 9 prefer B "
        "(p < 0.001)");
  const auto other = two_ac(7, 0, 0, 0.95, 1.0, "ref", "heavier");
  CHECK(other.ci_high == Approx(-0.999024927846106).epsilon(1e-6));
  CHECK(other.note == "nobody preferred heavier: d' is infinite and its interval open below");
  // Open above and no difference shown: what the data cannot exclude is any d' above the end.
  CHECK(two_ac(0, 2, 2).verdict ==
        "no evidence of a preference, but the data cannot exclude any d' above -0.27: d' inf "
        "[-0.27, inf], 0 prefer A, 2 same, 2 prefer B (p = 0.0959; equivalence margin 1.00)");
  const auto same = two_ac(0, 6, 0);
  CHECK(std::isnan(same.dprime));
  CHECK(same.note == "no interval: every answer was 'same', which the model cannot turn into a d'");
  CHECK(same.verdict == "no d': every answer was 'same' (6 answers)");
}

// The verdicts of identify-real, word for word: equivalent, inconclusive (the 9 of
// 16), a difference either way, and a difference inside the margin. The numbers are R's
// (binom.test's Clopper-Pearson interval, pbinom for the two one-sided tests;
// tests/study/r/equivalence.R).
TEST_CASE("identify-real's verdicts say what the data exclude, word for word", "[study]") {
  auto verdict = [](int correct, int n) {
    IdentifyReal r;
    r.panel = forced_choice_2afc(correct, n, 0.95, 1.0);
    r.margin = 1.0;
    return identify_verdict(r, 0.95);
  };
  const IdentifyReal equivalent = verdict(160, 300);
  CHECK(equivalent.conclusion == Conclusion::kEquivalent);
  CHECK(equivalent.verdict ==
        "indistinguishable: |d'| below 1.00 with 95 % confidence: d' 0.12 [-0.09, 0.32], 160 of "
        "300 correct (equivalence p < 0.001, two one-sided tests)");
  const IdentifyReal inconclusive = verdict(9, 16);
  CHECK(inconclusive.conclusion == Conclusion::kInconclusive);
  CHECK(inconclusive.verdict ==
        "no evidence of a difference, but the data cannot exclude |d'| up to 1.20: d' 0.22 "
        "[-0.75, 1.20], 9 of 16 correct (p = 0.804; equivalence margin 1.00)");
  CHECK(inconclusive.panel.p_equivalence == Approx(0.0654265867452477).epsilon(1e-10));
  const IdentifyReal different = verdict(60, 80);
  CHECK(different.conclusion == Conclusion::kDifferent);
  CHECK(different.verdict ==
        "the panel could tell the virtual door from the real one: d' 0.95 [0.51, 1.41], 60 of 80 "
        "correct (p < 0.001)");
  CHECK(verdict(20, 80).verdict ==
        "the panel took the virtual door for the real one more often than chance: d' -0.95 "
        "[-1.41, -0.51], 20 of 80 correct (p < 0.001)");
  const IdentifyReal small = verdict(5300, 10000);
  CHECK(small.conclusion == Conclusion::kDifferentWithinMargin);
  CHECK(small.verdict ==
        "a difference smaller than the margin: the panel told the doors apart above chance (p < "
        "0.001), but |d'| is below 1.00 with 95 % confidence: d' 0.11 [0.07, 0.14], 5300 of 10000 "
        "correct");
}

// The 2-AC verdicts, word for word, on counts whose numbers R gives (equivalence.R).
TEST_CASE("2-AC's verdicts name the variants and say what the data exclude, word for word",
          "[study]") {
  const auto equivalent = two_ac(60, 300, 80, 0.95, 1.0, "ref", "lighter");
  CHECK(equivalent.conclusion == Conclusion::kEquivalent);
  CHECK(equivalent.verdict ==
        "indistinguishable: |d'| below 1.00 with 95 % confidence: d' 0.13 [-0.02, 0.29], 60 prefer "
        "ref, 300 same, 80 prefer lighter (equivalence p < 0.001, two one-sided tests)");
  const auto inconclusive = two_ac(2, 2, 6);
  CHECK(inconclusive.conclusion == Conclusion::kInconclusive);
  CHECK(inconclusive.verdict ==
        "no evidence of a preference, but the data cannot exclude |d'| up to 1.86: d' 0.77 "
        "[-0.27, 1.86], 2 prefer A, 2 same, 6 prefer B (p = 0.148; equivalence margin 1.00)");
  CHECK(inconclusive.p_equivalence == Approx(0.339050774028284).epsilon(1e-5));
  const auto different = two_ac(5, 5, 30);
  CHECK(different.conclusion == Conclusion::kDifferent);
  CHECK(different.verdict ==
        "B preferred to A: d' 1.29 [0.71, 1.90], 5 prefer A, 5 same, 30 prefer B (p < 0.001)");
}

TEST_CASE("p-values are written as statisticians write them", "[study]") {
  CHECK(doorbench::format_p_value(1.8e-11) == "< 0.001");
  CHECK(doorbench::format_p_value(0.000999) == "< 0.001");
  CHECK(doorbench::format_p_value(0.001) == "0.001");
  CHECK(doorbench::format_p_value(0.0012345) == "0.00123");
  CHECK(doorbench::format_p_value(0.147975959) == "0.148");
  CHECK(doorbench::format_p_value(0.80362) == "0.804");
  CHECK(doorbench::format_p_value(0.99982) == "> 0.999");
  CHECK(doorbench::format_p_value(1.0) == "1");
  CHECK(doorbench::p_value_text(1.8e-11) == "p < 0.001");
  CHECK(doorbench::p_value_text(0.0345) == "p = 0.0345");
  CHECK(doorbench::format_fixed(-0.001, 2) == "0.00");
  CHECK(doorbench::format_fixed(-0.006, 2) == "-0.01");
}

TEST_CASE("2-AC pairs count answers whatever the presentation order", "[study]") {
  const auto table = parse_trials_table(kHeader +
                                            "P1,pair,1,preference-2ac,A,B,2\n"
                                            "P1,pair,2,preference-2ac,B,A,1\n"
                                            "P1,pair,3,preference-2ac,B,A,same\n"
                                            "P2,pair,1,preference-2ac,A,B,1\n"
                                            "P2,pair,2,preference-2ac,B,A,2\n"
                                            "P2,pair,3,preference,A,B,1\n",
                                        "t.csv");
  const auto pairs = two_ac_pairs(table);
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].first == "A");
  CHECK(pairs[0].second == "B");
  CHECK(pairs[0].prefer_first == 2);
  CHECK(pairs[0].no_preference == 1);
  CHECK(pairs[0].prefer_second == 2);
}

TEST_CASE("2-AC refuses an answer it does not know, naming the line", "[study]") {
  const auto table = parse_trials_table(kHeader + "P1,pair,1,preference-2ac,A,B,3\n", "t.csv");
  REQUIRE_THROWS_WITH(two_ac_pairs(table),
                      "t.csv:2: answer '3' to a preference-2ac question (expected 1, 2 or same)");
}

// Reference values from R 4.2 (independent): qbeta(0.025, 30, 21), qbeta(0.975, 31, 20),
// sqrt(2) * qnorm(0.6), binom.test(30, 50)$p.value.
TEST_CASE("2-AFC: Pc, d', the Clopper-Pearson interval and the exact test", "[study]") {
  const auto r = forced_choice_2afc(30, 50);
  CHECK(r.pc == Approx(0.6));
  CHECK(r.dprime == Approx(0.358286909242583).epsilon(1e-12));
  CHECK(r.pc_low == Approx(0.45179402847918).epsilon(1e-10));
  CHECK(r.pc_high == Approx(0.735921604905463).epsilon(1e-10));
  CHECK(r.ci_low == Approx(std::sqrt(2.0) * -0.1211).epsilon(1e-3));
  CHECK(r.p == Approx(0.202638751064541).epsilon(1e-10));
  const auto all = forced_choice_2afc(10, 10);
  CHECK(std::isinf(all.dprime));
  CHECK(std::isinf(all.ci_high));
  CHECK(std::isfinite(all.ci_low));
}

TEST_CASE("identify-real scores each participant and the panel, with a verdict", "[study]") {
  std::string text = kHeader;
  // P1: 4 of 6 correct; P2: 3 of 4. The real door is 'real', first or second.
  const char* rows[] = {"P1,ir,1,identify-real,real,V,1", "P1,ir,2,identify-real,V,real,2",
                        "P1,ir,3,identify-real,real,V,2", "P1,ir,4,identify-real,V,real,2",
                        "P1,ir,5,identify-real,real,V,1", "P1,ir,6,identify-real,V,real,1",
                        "P2,ir,1,identify-real,V,real,2", "P2,ir,2,identify-real,real,V,1",
                        "P2,ir,3,identify-real,real,V,2", "P2,ir,4,identify-real,V,real,2"};
  for (const char* row : rows) text += std::string(row) + "\n";
  const auto result = identify_real(parse_trials_table(text, "t.csv"));
  REQUIRE(result);
  REQUIRE(result->participants.size() == 2);
  CHECK(result->participants[0].participant == "P1");
  CHECK(result->participants[0].correct == 4);
  CHECK(result->participants[0].n == 6);
  CHECK(result->participants[1].correct == 3);
  CHECK(result->panel.correct == 7);
  CHECK(result->panel.n == 10);
  CHECK(result->verdict ==
        "no evidence of a difference, but the data cannot exclude |d'| up to 2.12: d' 0.74 "
        "[-0.55, 2.12], 7 of 10 correct (p = 0.344; equivalence margin 1.00)");
}

TEST_CASE("identify-real refuses a trial without the real door, naming the line", "[study]") {
  const auto table = parse_trials_table(kHeader + "P1,ir,1,identify-real,A,B,1\n", "t.csv");
  REQUIRE_THROWS_WITH(identify_real(table),
                      "t.csv:2: an identify-real trial must present the real door ('real') "
                      "once; it presents 'A' and 'B'");
  const auto none = parse_trials_table(kHeader + "P1,pair,1,preference,A,B,1\n", "t.csv");
  CHECK_FALSE(identify_real(none));
}
