#pragma once
// The exact binomial test of a two-choice answer against chance, for A/B runs and the
// panel's discrimination statistics.

namespace doorbench::study {

// The exact two-sided binomial test against chance 0.5: the probability, under chance, of
// an outcome at least as far from n/2 as k: twice the nearer tail, from Boost.Math's
// binomial distribution (the regularised incomplete beta function, to double precision;
// a far tail underflows to 0, tested to n = 10^7). k > n or negative throws
// std::invalid_argument. Thread-safe.
double binomial_two_sided_p(long k, long n);

}  // namespace doorbench::study
