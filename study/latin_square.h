#pragma once
// Balanced Latin squares (Williams designs) for the order of blocks and of variants across
// participants (docs/campaign.md, "Counterbalancing").
//
// For n conditions, n even: n rows; row r is r, r+1, r−1, r+2, r−2, ... (mod n). Each
// condition is in each position once, and each ordered pair (a directly before b, a ≠ b)
// occurs exactly once: first-order carry-over is balanced. For n odd no single square does
// that, so the design is the square and its mirror (each row reversed): 2n rows, each
// condition twice in each position, each ordered pair exactly twice (Williams 1949).
// Participant i takes row i mod rows: over a multiple of the rows everything is balanced.
// Thread safety: a free function.
#include <vector>

namespace doorbench::study {

// The rows of the design for n >= 1 conditions (n rows when n is even or 1, else 2n);
// std::invalid_argument for n < 1.
std::vector<std::vector<int>> williams_design(int n);

}  // namespace doorbench::study
