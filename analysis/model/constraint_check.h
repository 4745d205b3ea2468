#pragma once
// A small helper that checks a parameter table's constraints in order and keeps the
// first failure as a one-line message naming the parameter and the constraint.
#include <cmath>
#include <string>
#include <string_view>

#include "core/number_format.h"

namespace doorbench {

class ConstraintCheck {
 public:
  explicit ConstraintCheck(std::string_view model_name) : model_name_(model_name) {}

  bool ok() const { return message_.empty(); }
  const std::string& message() const { return message_; }

  void finite(std::string_view name, double value) {
    if (ok() && !std::isfinite(value)) fail(name, value, "is not a finite number", "");
  }
  // `holds` is the constraint's truth; `constraint` its text as in the spec's table;
  // `context` the other values it involves ("theta1 = 0.02"), or empty.
  void require(bool holds, std::string_view name, double value, std::string_view constraint,
               std::string context = "") {
    if (ok() && !holds) fail(name, value, "breaks " + std::string(constraint), context);
  }

 private:
  void fail(std::string_view name, double value, const std::string& what,
            const std::string& context) {
    message_ = std::string(model_name_) + " parameter " + std::string(name) + " = " +
               format_number(value) + " " + what;
    if (!context.empty()) message_ += " (" + context + ")";
  }

  std::string_view model_name_;
  std::string message_;
};

}  // namespace doorbench
