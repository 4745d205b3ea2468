// Every number checked where it enters: every numeric option of every verb,
// taken from the verbs' own option lists (the command line built as main() builds it, by
// add_all_verbs), refuses nan, inf, -inf, 1e308 and a non-number with a usage error naming
// the option; an unsigned one refuses -1. Values that pass the parse (-1 and 0 where an
// option takes them) are listed, so that a new option taking them is a decision. Parsing
// only: no verb runs. Contradicting options, and a handle radius where no door handle is.
#include <CLI/CLI.hpp>
#include <catch2/catch.hpp>
#include <set>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/number_options.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using namespace doorbench::app;

namespace {

// The command line as main() builds it.
struct Cli {
  CLI::App app{"doorbench"};
  bool quiet = false;
  Action action;
  Cli() {
    app.require_subcommand(1);
    app.add_flag("-q,--quiet", quiet, "");
    app.fallthrough(true);
    add_all_verbs(app, action);
  }
};

struct NumericOption {
  std::vector<std::string> verb;  // "calibrate", "geometry"
  std::string name;               // "--radius-m", or a positional's name
  bool positional = false;
  NumberKind kind = NumberKind::kNone;
  std::string label() const {
    std::string text;
    for (const std::string& word : verb) text += word + " ";
    return text + name;
  }
};

void collect(CLI::App& app, std::vector<std::string> verb, std::vector<NumericOption>& out) {
  for (CLI::Option* option : app.get_options()) {
    const NumberKind kind = number_kind(*option);
    if (kind == NumberKind::kNone) continue;
    const bool positional = option->get_lnames().empty() && option->get_snames().empty();
    out.push_back({verb, positional ? option->get_name(true) : "--" + option->get_lnames().front(),
                   positional, kind});
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    std::vector<std::string> path = verb;
    path.push_back(sub->get_name());
    collect(*sub, path, out);
  }
}

// How parsing `option` given `value` ended: "" accepted, else the error's message.
std::string parse_with(Cli& cli, const NumericOption& option, const std::string& value) {
  std::vector<std::string> args = option.verb;
  if (!option.positional) args.push_back(option.name);
  args.push_back(value);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11's order
  try {
    cli.app.parse(reversed);
  } catch (const CLI::ValidationError& error) {
    return error.what();
  } catch (const CLI::ConversionError& error) {
    return error.what();
  } catch (const CLI::ParseError& error) {
    return "";  // e.g. a required option missing: the value itself passed
  }
  return "";
}

// True when `said` ends in one of number_options.h's answers about `value`.
bool in_doorbench_words(const std::string& said, const std::string& value) {
  for (const std::string& answer :
       {"'" + value + "' is not a number", value + " is not a finite number",
        value + " is negative (0 or more)", value + " is not a whole number",
        value + " is not positive (more than 0)"}) {
    if (said.size() >= answer.size() &&
        said.compare(said.size() - answer.size(), answer.size(), answer) == 0) {
      return true;
    }
  }
  for (const std::string& start : {": " + value + " is beyond ", ": " + value + " is outside "}) {
    if (said.find(start) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("CLI numbers: the check of one value", "[cli][numbers]") {
  CHECK(number_problem("2.5", NumberKind::kFloat).empty());
  CHECK(number_problem("-1e3", NumberKind::kFloat).empty());
  CHECK(number_problem("nan", NumberKind::kFloat) == "nan is not a finite number");
  CHECK(number_problem("-inf", NumberKind::kFloat) == "-inf is not a finite number");
  CHECK(number_problem("1e308", NumberKind::kFloat) ==
        "1e308 is beyond 1000000000, the largest value any option takes");
  CHECK(number_problem("abc", NumberKind::kInt) == "'abc' is not a number");
  CHECK(number_problem(" 1", NumberKind::kFloat) == "' 1' is not a number");
  CHECK(number_problem("1.5", NumberKind::kInt) == "1.5 is not a whole number");
  CHECK(number_problem("-1", NumberKind::kUint) == "-1 is negative (0 or more)");
  CHECK(number_problem("-1", NumberKind::kInt).empty());
  CHECK(number_problem(std::string(100, '7'), NumberKind::kInt) ==
        std::string(60, '7') +
            "... (100 characters) is beyond the whole numbers this option takes");
}

TEST_CASE("CLI numbers: every numeric option of every verb refuses what is not a usable number",
          "[cli][numbers]") {
  Cli cli;
  std::vector<NumericOption> options;
  collect(cli.app, {}, options);
  std::set<std::string> labels;
  for (const NumericOption& option : options) labels.insert(option.label());
  // The list is the verbs' own: these are among them (the cases).
  for (const char* known : {"record --duration-s", "calibrate loadcell --window-s",
                            "simulate --rate-hz", "spec --samples", "spec --lambda", "spec --seed",
                            "play --max-tick-interval-ms", "calibrate geometry --radius-m"}) {
    INFO(known);
    CHECK(labels.count(known) == 1);
  }
  CHECK(options.size() > 40);
  std::set<std::string> accepted;
  int refusals = 0;
  for (const NumericOption& option : options) {
    std::vector<std::string> values = {"nan", "inf", "-inf", "1e308", "abc", "-1", "0"};
    for (const std::string& value : values) {
      INFO(option.label() << " " << value);
      const std::string said = parse_with(cli, option, value);
      if (said.empty()) {
        // Only -1 and 0 may pass, and only where the option takes them (listed below).
        CHECK((value == "-1" || value == "0"));
        accepted.insert(option.label() + " " + value);
        continue;
      }
      ++refusals;
      CHECK_THAT(said, StartsWith(option.positional ? option.name : option.name + ": "));
      CHECK_THAT(said, Contains(value));
      // In doorbench's words, never CLI11's ("Value abc not in range 0.000000 to 1797...").
      CHECK(in_doorbench_words(said, value));
      if (value == "-1" && option.kind == NumberKind::kUint) {
        CHECK_THAT(said, Contains("-1 is negative (0 or more)"));
      }
    }
  }
  CHECK(refusals >= static_cast<int>(options.size()) * 5);
  // Where -1 or 0 is a value the option takes (e.g. a seed 0, "0: all cores", an offset).
  const std::set<std::string> takes_them = {
      // angles and forces that may be 0 or negative
      "calibrate geometry --angle-deg -1", "calibrate geometry --angle-deg 0",
      "calibrate geometry --check-reading-N -1", "calibrate geometry --check-reading-N 0",
      "calibrate geometry --check-reference-N -1", "calibrate geometry --check-reference-N 0",
      "calibrate inclinometer --angles-deg -1", "calibrate inclinometer --angles-deg 0",
      "calibrate loadcell --forces-N -1", "calibrate loadcell --forces-N 0",
      // 0: unloaded, none, the default rule, the rig's, all cores, a seed, every window
      "calibrate loadcell --masses-kg 0", "calibrate gyro --inclinometer-range-deg 0",
      "calibrate inclinometer --inclinometer-range-deg 0",
      "calibrate timing --inclinometer-range-deg 0", "fit --derivative-cutoff-hz 0",
      "fit --folds 0", "fit --force-cutoff-hz 0", "fit --hops 0", "fit --max-windows 0",
      "fit --repolish 0", "loop --derivative-cutoff-hz 0", "loop --force-cutoff-hz 0",
      "play --push-N 0", "play --pushes-hz 0", "play --seed 0", "record --max-wait-s 0",
      "spec --lambda 0", "spec --seed 0", "spec --threads 0", "ab --seed 0",
      "campaign analyze --bootstrap 0", "campaign analyze --seed 0", "campaign plan --seed 0",
      // the station's nice value 0: not lowered
      "play --station-nice 0", "ab --station-nice 0", "campaign run --station-nice 0"};
  std::string listed;
  for (const std::string& a : accepted) listed += "\"" + a + "\",\n";
  INFO("accepted:\n" << listed);
  CHECK(accepted == takes_them);
}

TEST_CASE("CLI numbers: the usage error main() prints names the option", "[cli][numbers]") {
  Cli cli;
  const auto said = [&](std::vector<std::string> args) {
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    try {
      cli.app.parse(reversed);
    } catch (const CLI::ParseError& error) {
      CHECK(error.get_exit_code() != 0);
      return std::string(error.what());
    }
    return std::string();
  };
  CHECK(said({"record", "--duration-s", "nan"}) == "--duration-s: nan is not a finite number");
  CHECK(said({"spec", "--seed", "-1"}) == "--seed: -1 is negative (0 or more)");
  CHECK(said({"spec", "--samples", "2000000000"}) ==
        "--samples: 2000000000 is outside 2 to 1000000");
  CHECK(said({"spec", "--lambda", "1e308"}) ==
        "--lambda: 1e308 is beyond 1000000000, the largest value any option takes");
  CHECK(said({"simulate", "--rate-hz", "nan"}) == "--rate-hz: nan is not a finite number");
  // Options with a range of their own answer in the same words: the text is checked first.
  CHECK(said({"fit", "x.csv", "--out", "o", "--derivative-cutoff-hz", "abc"}) ==
        "--derivative-cutoff-hz: 'abc' is not a number");
  CHECK(said({"fit", "x.csv", "--out", "o", "--derivative-cutoff-hz", "-1"}) ==
        "--derivative-cutoff-hz: -1 is negative (0 or more)");
  CHECK(said({"fit", "x.csv", "--out", "o", "--min-sample-rate-hz", "0"}) ==
        "--min-sample-rate-hz: 0 is not positive (more than 0)");
  CHECK(said({"import", "x.csv", "--out", "o.h5", "--resample-hz", "0.5"}) ==
        "--resample-hz: 0.5 is outside 1 to 1000000");
  CHECK(said({"import", "x.csv", "--out", "o.h5", "--resample-hz", "1e308"}) ==
        "--resample-hz: 1e308 is beyond 1000000000, the largest value any option takes");
}

TEST_CASE("CLI numbers: options that contradict each other or would be ignored are refused",
          "[cli][numbers]") {
  Cli cli;
  const doorbench::testing::TempDir dir("contradictions");
  const std::string file = dir.write("tol.json", "{}").string();
  const auto said = [&](std::vector<std::string> args) {
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    try {
      cli.app.parse(reversed);
    } catch (const CLI::ParseError& error) {
      CHECK(error.get_exit_code() != 0);
      return std::string(error.what());
    }
    return std::string();
  };
  CHECK(said({"calibrate", "loadcell", "--tare", "--masses-kg", "1,2"}) ==
        "--masses-kg excludes --tare");
  CHECK(said({"calibrate", "loadcell", "--forces-N", "10", "--tare"}) ==
        "--forces-N excludes --tare");
  CHECK(said({"spec", file, "--asis", file, "--out", "x", "--no-tolerances", "--tolerances",
              file}) == "--tolerances excludes --no-tolerances");
  CHECK(said({"spec", file, "--asis", file, "--out", "x", "--samples", "20", "--no-tolerances"}) ==
        "--samples excludes --no-tolerances");
  // A parameter free and held: refused before anything is read.
  const doorbench::testing::DoorbenchRun run = doorbench::testing::run_doorbench_shell(
      "fit no-such.csv --out '" + (dir / "out").string() + "' --free J,d1 --fixed J", dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --free and --fixed both name J (a parameter is free or held) (see doorbench "
        "fit --help)\n");
}

TEST_CASE("CLI numbers: a handle radius outside 0.05 to 2 m is refused unless --force-geometry",
          "[cli][numbers]") {
  const doorbench::testing::TempDir dir("radius");
  auto run = doorbench::testing::run_doorbench_shell(
      "calibrate geometry --radius-m 0.7,1e3 --angle-deg 0", dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --radius-m: 1000 m is outside 0.05 to 2 m, where a door handle is; give "
        "--force-geometry to use it anyway (see doorbench calibrate geometry --help)\n");
  run = doorbench::testing::run_doorbench_shell(
      "calibrate geometry --radius-m 1e308 --angle-deg 0 --force-geometry", dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --radius-m: 1e308 is beyond 1000000000, the largest value any "
        "option takes (see doorbench calibrate geometry --help)\n");
  // A CSV stating 1e9 m.
  const std::string csv = doorbench::testing::simulate_open_close_csv(dir, "run.csv", 6.0, 200.0);
  REQUIRE(!csv.empty());
  std::string text = doorbench::testing::read_file(csv);
  const auto at = text.find("# handle_radius_m: 0.58\n");
  REQUIRE(at != std::string::npos);
  text.replace(at, 24, "# handle_radius_m: 1e9\n");
  const std::string far = dir.write("far.csv", text).string();
  run = doorbench::testing::run_doorbench_shell(
      "fit '" + far + "' --out '" + (dir / "fit").string() + "'", dir);
  CHECK(run.status == 2);
  CHECK(run.err == "preparing " + far +
                       "\ndoorbench: handle radius 1e+09 m (from the CSV's metadata (# "
                       "handle_radius_m)) is outside 0.05 to 2 m, where a door handle is; give "
                       "--force-geometry to use it anyway (see doorbench fit --help)\n");
  CHECK(!std::filesystem::exists(dir / "fit"));
}
