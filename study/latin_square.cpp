#include "study/latin_square.h"

#include <stdexcept>
#include <string>

namespace doorbench::study {

std::vector<std::vector<int>> williams_design(int n) {
  if (n < 1)
    throw std::invalid_argument("williams_design: n must be at least 1, got " + std::to_string(n));
  // The first row's offsets: 0, 1, −1, 2, −2, ... (mod n).
  std::vector<int> offsets;
  offsets.push_back(0);
  for (int k = 1; static_cast<int>(offsets.size()) < n; ++k) {
    offsets.push_back(k);
    if (static_cast<int>(offsets.size()) < n) offsets.push_back(-k);
  }
  std::vector<std::vector<int>> rows;
  for (int r = 0; r < n; ++r) {
    std::vector<int> row;
    for (int offset : offsets) row.push_back(((r + offset) % n + n) % n);
    rows.push_back(row);
  }
  if (n % 2 == 1 && n > 1) {
    for (int r = 0; r < n; ++r) rows.push_back(std::vector<int>(rows[r].rbegin(), rows[r].rend()));
  }
  return rows;
}

}  // namespace doorbench::study
