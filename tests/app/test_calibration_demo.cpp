// The calibration demo (app/calibration_demo.cpp) runs, recovers the sensors' known
// errors and reduces every error against the truth.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <sstream>

#include "app/calibration_demo.h"

TEST_CASE("Calibration demo: errors before and after", "[calibration][demo]") {
  std::ostringstream out;
  const auto start = std::chrono::steady_clock::now();
  doorbench::app::run_calibration_demo(out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  INFO(out.str());
  CHECK(seconds < 20.0);
  const std::string text = out.str();
  CHECK(text.find("errors against the truth") != std::string::npos);
  CHECK(text.find("[1/11] remove every load from the cell, then press Enter") != std::string::npos);
  // Each error against the truth falls: "before" and "after" columns of the table.
  for (const char* row :
       {"force at rest (mean)", "force in strokes (rms)", "inclinometer, |θ| < 9° (rms)",
        "rate at rest (mean)", "rate moving (rms)"}) {
    const std::size_t at = text.find(row);
    REQUIRE(at != std::string::npos);
    std::istringstream line(text.substr(at + std::string(row).size()));
    double before = 0, after = 0;
    line >> before >> after;
    INFO(row);
    CHECK(std::abs(after) < 0.5 * std::abs(before));
  }
  CHECK_THAT(text, Catch::Contains("(truth -2.500 N)"));
  CHECK_THAT(text, Catch::Contains("(truth 0.4000°)"));
}
