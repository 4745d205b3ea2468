#pragma once
// Every number given on the command line is checked where it enters: one
// validator, attached by check_numeric_options() to every numeric option of every verb
// (and of their sub-verbs) after they are registered, so that a new option is covered by
// itself. An option is numeric when CLI11 gives its type as FLOAT, INT or UINT (a vector of
// them too). Its values must then
//   - be numbers: "--rate-hz: 'abc' is not a number";
//   - be finite: "--duration-s: nan is not a finite number" (also inf, -inf);
//   - for UINT, not be negative: "--seed: -1 is negative (0 or more)", where C++ would
//     otherwise wrap it around to 18446744073709551615;
//   - lie within the option's range: its own number_range() (or non_negative_number(),
//     positive_number()) where the verb gives one, else the range listed for it in
//     number_options.cpp (kRanges), else |x| <= 1e9 for FLOAT
//     ("--lambda: 1e+308 is beyond 1e+09, the largest value any option takes").
// The check runs before any other check of the option, so that no text reaches CLI11's
// own validators (CLI::Range answers "Value abc not in range 0.000000 to 1797...": a verb
// uses number_range() instead, which speaks as the rest of doorbench does).
// A refusal is a CLI::ValidationError naming the option: main() prints it and exits 2.
// Not thread-safe (it changes `app`); call once, before parsing.
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace doorbench::app {

enum class NumberKind { kNone, kFloat, kInt, kUint };

// What CLI11 says `option` holds (its type name before any ':').
NumberKind number_kind(const CLI::Option& option);

// Attaches the check to every numeric option of `app` and its subcommands, recursively.
void check_numeric_options(CLI::App& app);

// The checks above for one value, "" when it passes (used by the validator; tested).
std::string number_problem(const std::string& text, NumberKind kind);

// A verb's own range for an option, inclusive: "0.5 is outside 1 to 1000000".
CLI::Validator number_range(double min, double max);
// 0 or more: "-1 is negative (0 or more)".
CLI::Validator non_negative_number();
// More than 0: "0 is not positive (more than 0)".
CLI::Validator positive_number();

}  // namespace doorbench::app
