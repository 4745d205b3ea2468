#pragma once
// The recording the loop's command-line tests run on (tests/app/test_loop_result.cpp,
// test_loop_interrupt.cpp): the sensory reference door with a gravity imbalance (g1 = 3 N·m)
// and viscous damping (b = 0.5 N·m·s/rad) its start model lacks, a 10 s open-close at 200 Hz
// made by `doorbench simulate` into DIR/run.csv. Returns the CSV's path; fails the test when
// simulate fails. Header-only, test code.
#include <catch2/catch.hpp>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace doorbench::testing {

inline std::string simulate_loop_recording(const TempDir& dir) {
  const std::string effects =
      dir.write("effects.json",
                R"({"gravity_imbalance": {"g1": 3.0}, "viscous_damping": {"b": 0.5}})")
          .string();
  const std::string csv = (dir / "run.csv").string();
  REQUIRE(run_doorbench_shell("simulate --model sensory --effects '" + effects +
                                  "' --hand open-close --duration-s 10 --rate-hz 200 --out '" +
                                  csv + "'",
                              dir)
              .status == 0);
  return csv;
}

}  // namespace doorbench::testing
