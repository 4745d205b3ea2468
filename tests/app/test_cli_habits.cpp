// Command-line habits: -V as --version, `doorbench help VERB` as
// `doorbench VERB --help`, --quiet before or after the verb, and usage errors that point at
// the verb's own help.
#include <catch2/catch.hpp>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

TEST_CASE("CLI habits: -V, help VERB, --quiet, errors naming the verb's help", "[cli]") {
  const TempDir dir("cli_habits");
  SECTION("-V is --version") {
    const auto v = run_doorbench_shell("-V", dir);
    const auto version = run_doorbench_shell("--version", dir);
    CHECK(v.status == 0);
    CHECK(v.out.rfind("doorbench ", 0) == 0);
    CHECK(v.out == version.out);
  }
  SECTION("help VERB prints the verb's --help") {
    for (const std::string verb : {"fit", "view", "hapticmaster check", ""}) {
      INFO("verb '" << verb << "'");
      const auto help = run_doorbench_shell("help " + verb, dir);
      const auto dash = run_doorbench_shell(verb + " --help", dir);
      CHECK(help.status == 0);
      CHECK(help.err.empty());
      CHECK(help.out == dash.out);
      CHECK(help.out.find("Usage:") != std::string::npos);
    }
    const auto unknown = run_doorbench_shell("help fitt", dir);
    CHECK(unknown.status == 2);
    CHECK(unknown.err.rfind("doorbench: help: unknown verb 'fitt' (expected ", 0) == 0);
    CHECK(unknown.err.find(") (see doorbench --help)\n") != std::string::npos);
  }
  SECTION("usage errors point at the verb's own help") {
    auto r = run_doorbench_shell("info --no-such-option x.h5", dir);
    CHECK(r.status == 2);
    CHECK(r.err ==
          "doorbench: The following argument was not expected: --no-such-option "
          "(see doorbench info --help)\n");
    r = run_doorbench_shell("model torque --out x.csv", dir);
    CHECK(r.status == 2);
    CHECK(r.err == "doorbench: --in is required (see doorbench model torque --help)\n");
    r = run_doorbench_shell("hapticmaster check --no-such-option", dir);
    CHECK(r.status == 2);
    CHECK(r.err.find("(see doorbench hapticmaster check --help)\n") != std::string::npos);
    // Without a verb, the command's help.
    r = run_doorbench_shell("--no-such-option", dir);
    CHECK(r.status == 2);
    CHECK(r.err.find("(see doorbench --help)\n") != std::string::npos);
    // A mistyped verb asking for help is still a mistake (exit 2, not 0 with the general help).
    r = run_doorbench_shell("NOSUCHVERB --help", dir);
    CHECK(r.status == 2);
    CHECK(r.out.empty());
    CHECK(r.err.rfind("doorbench: unknown verb 'NOSUCHVERB' (expected model, simulate, ", 0) == 0);
    CHECK(r.err.find(") (see doorbench --help)\n") != std::string::npos);
  }
  SECTION("--quiet silences record's live status, written with stdio") {
    const std::string out = (dir / "q.h5").string();
    const auto loud = run_doorbench_shell("record --duration-s 0.3 --out '" + out + "'", dir);
    REQUIRE(loud.status == 0);
    REQUIRE_FALSE(loud.err.empty());
    const auto quiet = run_doorbench_shell("record -q --duration-s 0.3 --out '" + out + "2'", dir);
    CHECK(quiet.status == 0);
    CHECK(quiet.err.empty());
    // Its error still shows.
    const auto failing = run_doorbench_shell("record -q --duration-s 0.3 --out '" + out + "'", dir);
    CHECK(failing.status == 2);
    CHECK(failing.err == "doorbench: " + out + ": exists (sessions are never overwritten)\n");
  }
  SECTION("--quiet drops stderr's progress lines, keeps stdout and errors") {
    const std::string csv = (dir / "sim.csv").string();
    const std::string args =
        "simulate --model sensory --hand open-close --duration-s 2 --rate-hz 200 --out ";
    const auto loud = run_doorbench_shell(args + "'" + csv + "'", dir);
    REQUIRE(loud.status == 0);
    REQUIRE_FALSE(loud.err.empty());  // it says what it wrote
    const auto quiet_after = run_doorbench_shell(args + "'" + csv + "2' --quiet", dir);
    CHECK(quiet_after.status == 0);
    CHECK(quiet_after.err.empty());
    const auto quiet_before = run_doorbench_shell("-q " + args + "'" + csv + "3'", dir);
    CHECK(quiet_before.status == 0);
    CHECK(quiet_before.err.empty());
    // An error still shows, on one line.
    const auto failing =
        run_doorbench_shell("--quiet info '" + (dir / "none.h5").string() + "'", dir);
    CHECK(failing.status != 0);
    CHECK(failing.err.rfind("doorbench: ", 0) == 0);
  }
}
