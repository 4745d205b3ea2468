#pragma once
// Simulated panels with a known truth for the statistics' tests: paired comparisons drawn
// from the Bradley–Terry/Davidson model with an order effect and participant heterogeneity
// (each participant's worths are the panel's plus N(0, sd²) per variant), 2-AFC
// identify-real answers from a known Pc, 2-AC answers from a known (tau, d'). The text is
// a trials.csv with the seven columns. Deterministic for a seed (own uniform and normal
// draws from std::mt19937_64's bits).
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

#include "core/seeded_random.h"

namespace doorbench::testing {

class PanelRandom {
 public:
  explicit PanelRandom(std::uint64_t seed) : generator_(seed) {}
  double uniform() { return uniform_open01(generator_); }
  double normal() { return standard_normal(generator_); }

 private:
  std::mt19937_64 generator_;
};

inline const char* kTrialsHeader = "participant,block,trial,question,first,second,answer\n";

// Appends one row, the fields joined by commas (piece by piece: GCC 12's -Wrestrict
// misfires on `"S" + std::to_string(n)`).
inline void append_row(std::string& out, std::initializer_list<std::string> fields) {
  bool first = true;
  for (const std::string& field : fields) {
    if (!first) out += ',';
    out += field;
    first = false;
  }
  out += '\n';
}

struct PairPanel {
  std::vector<std::string> variants{"A", "B", "C", "D"};
  std::vector<double> worths{0.0, 0.5, -0.3, 1.0};  // log scale, first at 0
  double delta = 0.0;                               // first-position advantage
  double nu = 0.0;  // Davidson's tie parameter (0: preference, else preference-2ac)
  double heterogeneity_sd = 0.0;
  int participants = 10;
  int repetitions = 2;  // each ordered pair this often per participant
};

// The rows (no header) of a simulated pair block.
inline std::string simulate_pairs(const PairPanel& panel, std::uint64_t seed) {
  PanelRandom random(seed);
  std::string rows;
  const std::string question = panel.nu > 0 ? "preference-2ac" : "preference";
  const std::size_t k = panel.variants.size();
  for (int p = 0; p < panel.participants; ++p) {
    std::vector<double> worth = panel.worths;
    for (double& w : worth) w += panel.heterogeneity_sd * random.normal();
    int trial = 0;
    for (int r = 0; r < panel.repetitions; ++r) {
      for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = 0; j < k; ++j) {
          if (i == j) continue;
          const double a = std::exp(worth[i] + panel.delta), b = std::exp(worth[j]);
          const double t = panel.nu * std::sqrt(a * b);
          const double u = random.uniform() * (a + b + t);
          const std::string answer = u < a ? "1" : u < a + b ? "2" : "same";
          append_row(rows, {std::string("S").append(std::to_string(p + 1)), "pair",
                            std::to_string(++trial), question, panel.variants[i], panel.variants[j],
                            answer});
        }
      }
    }
  }
  return rows;
}

// identify-real rows: each participant `trials` trials, correct with probability pc.
inline std::string simulate_identify_real(double pc, int participants, int trials,
                                          std::uint64_t seed) {
  PanelRandom random(seed);
  std::string rows;
  for (int p = 0; p < participants; ++p) {
    for (int t = 0; t < trials; ++t) {
      const bool real_first = t % 2 == 0;
      const bool correct = random.uniform() < pc;
      const std::string answer = (real_first == correct) ? "1" : "2";
      append_row(rows,
                 {std::string("R").append(std::to_string(p + 1)), "ir", std::to_string(t + 1),
                  "identify-real", real_first ? "real" : "V", real_first ? "V" : "real", answer});
    }
  }
  return rows;
}

// 2-AC counts (prefer A, none, prefer B) of n answers from the Thurstonian model.
inline std::vector<int> simulate_two_ac(double tau, double dprime, int n, std::uint64_t seed) {
  PanelRandom random(seed);
  std::vector<int> counts(3, 0);
  for (int k = 0; k < n; ++k) {
    const double x = dprime + std::sqrt(2.0) * random.normal();
    ++counts[x < -tau ? 0 : x > tau ? 2 : 1];
  }
  return counts;
}

}  // namespace doorbench::testing
