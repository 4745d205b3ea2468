#include "app/number_options.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <utility>

#include "core/number_format.h"

namespace doorbench::app {

namespace {

// Ranges of options whose verb gives none itself and whose underlying Options' validate()
// would otherwise see the value only after work began (or never, e.g. an allocation).
struct NamedRange {
  const char* verb;  // the verb's path, "calibrate geometry"
  const char* option;
  double min, max;
};
constexpr NamedRange kRanges[] = {
    {"spec", "--samples", 2, 1e6},  // the Monte Carlo's samples (tolerance_analysis: >= 2)
    {"spec", "--threads", 0, 1024},
    {"spec", "--lambda", 0, 1e9},
    {"spec", "--starts", 1, 32},             // InverseDesignOptions::validate()
    {"ab", "--presentation-s", 0.01, 3600},  // AbOptions::validate(): > 0, at most an hour
    {"view", "--width", 200, 16384},         // WindowOptions::validate()
    {"view", "--height", 150, 16384},
    {"view", "--window-s", 0.001, 86400},  // LiveOptions::validate(): > 0
    {"view", "--live-samples", 2, 1e9},
    {"calibrate gyro", "--inclinometer-range-deg", 0, 360},  // 0: the rig's
    {"calibrate inclinometer", "--inclinometer-range-deg", 0, 360},
    {"calibrate timing", "--inclinometer-range-deg", 0, 360},
    {"calibrate loadcell", "--masses-kg", 0, 10000},
    // Physical bounds (0.05 to 2 m) are checked by the verb, which --force-geometry lifts.
    {"calibrate geometry", "--radius-m", 0.001, 1000},
    // d' 0.05 is Pc 51.4 % in 2-AFC, d' 5 is 99.98 %: margins outside say nothing.
    {"campaign analyze", "--equivalence-dprime", 0.05, 5},
};

constexpr double kLargestValue = 1e9;

std::string shown(const std::string& text) {
  // Long values are cut, with their size: a 10 MB value is not echoed on one line.
  if (text.size() <= 80) return text;
  return text.substr(0, 60) + "... (" + std::to_string(text.size()) + " characters)";
}

// The verb's path: "spec", "calibrate geometry".
std::string verb_path(const CLI::App* app) {
  std::string path;
  for (; app != nullptr && app->get_parent() != nullptr; app = app->get_parent()) {
    path = app->get_name() + (path.empty() ? "" : " " + path);
  }
  return path;
}

CLI::Validator number_validator(NumberKind kind, const NamedRange* range) {
  return CLI::Validator(
      [kind, range](std::string& text) -> std::string {
        std::string problem = number_problem(text, kind);
        if (!problem.empty() || range == nullptr) return problem;
        const double value = std::strtod(text.c_str(), nullptr);
        if (value < range->min || value > range->max) {
          return text + " is outside " + format_readable(range->min) + " to " +
                 format_readable(range->max);
        }
        return "";
      },
      "");  // no description: the help keeps its type names
}

void check_recursively(CLI::App& app) {
  const std::string verb = verb_path(&app);
  for (CLI::Option* option : app.get_options()) {
    const NumberKind kind = number_kind(*option);
    if (kind == NumberKind::kNone) continue;
    const NamedRange* range = nullptr;
    for (const NamedRange& named : kRanges) {
      if (verb == named.verb && option->check_lname(std::string(named.option).substr(2))) {
        range = &named;
      }
    }
    // In front of the verb's own checks: a text that is no number is answered here.
    option->transform(number_validator(kind, range));
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    check_recursively(*sub);
  }
}

}  // namespace

NumberKind number_kind(const CLI::Option& option) {
  std::string type = option.get_type_name();
  type = type.substr(0, type.find(':'));
  if (type == "FLOAT") return NumberKind::kFloat;
  if (type == "INT") return NumberKind::kInt;
  if (type == "UINT") return NumberKind::kUint;
  return NumberKind::kNone;
}

std::string number_problem(const std::string& text, NumberKind kind) {
  if (kind == NumberKind::kNone) return "";
  const char* const begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  const bool whole =
      end != begin && *end == '\0' && !std::isspace(static_cast<unsigned char>(text[0]));
  if (!whole) return "'" + shown(text) + "' is not a number";
  if (!std::isfinite(value)) return shown(text) + " is not a finite number";
  if (kind == NumberKind::kUint && text.find('-') != std::string::npos) {
    return shown(text) + " is negative (0 or more)";
  }
  if (kind != NumberKind::kFloat &&
      text.find_first_not_of("0123456789", text[0] == '-' || text[0] == '+' ? 1 : 0) !=
          std::string::npos) {
    return shown(text) + " is not a whole number";
  }
  if (kind != NumberKind::kFloat && std::fabs(value) > 9.2e18) {
    return shown(text) + " is beyond the whole numbers this option takes";
  }
  if (kind == NumberKind::kFloat && std::fabs(value) > kLargestValue) {
    return shown(text) + " is beyond " + format_readable(kLargestValue) +
           ", the largest value any option takes";
  }
  return "";
}

void check_numeric_options(CLI::App& app) {
  check_recursively(app);
}

namespace {

// A check of a number against `within` (true: it passes), else "TEXT" + `otherwise`.
CLI::Validator value_check(std::function<bool(double)> within, std::string otherwise,
                           std::string description) {
  return CLI::Validator(
      [within = std::move(within), otherwise = std::move(otherwise)](std::string& text) {
        if (std::string problem = number_problem(text, NumberKind::kFloat); !problem.empty()) {
          return problem;
        }
        return within(std::strtod(text.c_str(), nullptr)) ? std::string() : text + otherwise;
      },
      std::move(description));
}

}  // namespace

CLI::Validator number_range(double min, double max) {
  return value_check([min, max](double value) { return value >= min && value <= max; },
                     " is outside " + format_readable(min) + " to " + format_readable(max),
                     format_readable(min) + " to " + format_readable(max));
}

CLI::Validator non_negative_number() {
  return value_check([](double value) { return value >= 0; }, " is negative (0 or more)",
                     "0 or more");
}

CLI::Validator positive_number() {
  return value_check([](double value) { return value > 0; }, " is not positive (more than 0)",
                     "more than 0");
}

}  // namespace doorbench::app
