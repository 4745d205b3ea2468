// The doorbench command, run for real as a child process (the path of the built executable
// comes in as DOORBENCH_EXECUTABLE): help for every verb, exit status 0/1/2, one-line error
// messages that name the file, line and key, and the files `model torque`, `simulate` and
// `demo` write, read back with the project's own CSV readers and compared with the spec
// and with the models evaluated in this process.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <catch2/catch.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/session/csv_table.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_file.h"
#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "core/units.h"
#include "tests/support/files.h"

using doorbench::kRadPerDeg;
using doorbench::testing::read_file;

using Catch::Matchers::Contains;
using Catch::Matchers::EndsWith;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinRel;
using doorbench::ModelKind;
namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------
// Running the command

struct RunResult {
  int exit_code = -1;  // the exit status; -SIGNAL when killed by a signal
  std::string out;
  std::string err;
};

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  REQUIRE(out.good());
}

// A fresh scratch folder per test, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("doorbench_test_cli_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path file = path_ / name;
    write_text(file, text);
    return file;
  }

 private:
  fs::path path_;
};

// Runs DOORBENCH_EXECUTABLE with `args` in folder `cwd` (stdin from /dev/null, stdout and
// stderr to files in `scratch`), waits at most 15 min, and returns its status and output.
// The limit only stops a hung run: these machines are shared, and the demo alone takes
// 35 s on an idle one.
RunResult run_doorbench(const std::vector<std::string>& args, const ScratchDir& scratch,
                        std::optional<fs::path> cwd = std::nullopt) {
  static int run_count = 0;
  const std::string tag = std::to_string(run_count++);
  const fs::path out_path = scratch / ("stdout_" + tag + ".txt");
  const fs::path err_path = scratch / ("stderr_" + tag + ".txt");
  const std::string executable = DOORBENCH_EXECUTABLE;
  const std::string out_file = out_path.string();
  const std::string err_file = err_path.string();
  const std::string work_dir = cwd ? cwd->string() : scratch.path().string();

  // Everything the child needs is prepared before fork(): after it, only system calls.
  std::vector<std::string> argv_storage = {executable};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& arg : argv_storage) argv.push_back(arg.data());
  argv.push_back(nullptr);

  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const int in_fd = ::open("/dev/null", O_RDONLY);
    const int out_fd = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in_fd < 0 || out_fd < 0 || err_fd < 0) ::_exit(126);
    if (::dup2(in_fd, 0) < 0 || ::dup2(out_fd, 1) < 0 || ::dup2(err_fd, 2) < 0) ::_exit(126);
    if (::chdir(work_dir.c_str()) != 0) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }

  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(15);
  for (;;) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) FAIL("waitpid failed: errno " << errno);
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      FAIL("doorbench did not finish within 15 min");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }

  RunResult result;
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.exit_code = -WTERMSIG(status);
  }
  result.out = read_file(out_path);
  result.err = read_file(err_path);
  REQUIRE(result.exit_code != 126);  // the child could not set itself up
  REQUIRE(result.exit_code != 127);  // execv failed: DOORBENCH_EXECUTABLE is not there
  return result;
}

std::string describe(const std::vector<std::string>& args) {
  std::string text = "doorbench";
  for (const std::string& arg : args) text += " " + arg;
  return text;
}

// stderr is exactly one line, "doorbench: ...\n".
void require_one_error_line(const RunResult& result) {
  INFO("stderr: " << result.err);
  REQUIRE_THAT(result.err, StartsWith("doorbench: "));
  REQUIRE_THAT(result.err, EndsWith("\n"));
  REQUIRE(std::count(result.err.begin(), result.err.end(), '\n') == 1);
}

// A failure (exit 1) with one error line, nothing on stdout.
void require_failure(const RunResult& result) {
  INFO("stdout: " << result.out << "\nstderr: " << result.err);
  REQUIRE(result.exit_code == 1);
  REQUIRE(result.out.empty());
  require_one_error_line(result);
}

void require_usage_error(const RunResult& result) {
  INFO("stdout: " << result.out << "\nstderr: " << result.err);
  REQUIRE(result.exit_code == 2);
  REQUIRE(result.out.empty());
  require_one_error_line(result);
}

void require_success(const RunResult& result) {
  INFO("stdout: " << result.out << "\nstderr: " << result.err);
  REQUIRE(result.exit_code == 0);
}

// ---------------------------------------------------------------------------------------
// Files

nlohmann::ordered_json reference_json() {
  return nlohmann::ordered_json::parse(doorbench::reference_door_json());
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

const std::vector<std::string> kSensoryTerms = {"unlatch", "snap", "latch", "friction", "stops"};
const std::vector<std::string> kPhysicalTerms = {
    "gravity", "spring", "hinge_friction", "guide_friction", "latch", "seal", "stops"};

const std::vector<std::string>& term_names(ModelKind kind) {
  return kind == ModelKind::kSensory ? kSensoryTerms : kPhysicalTerms;
}

std::string model_name(ModelKind kind) {
  return std::string(doorbench::to_string(kind));
}

// A grid that crosses the latch, free movement and both end stops, in both directions.
constexpr std::array<double, 11> kGridTheta = {-0.01, 0.0, 0.003, 0.00698, 0.02, 0.03,
                                               0.05,  0.5, 1.0,   1.5,     1.6};
constexpr std::array<double, 3> kGridOmega = {-0.5, 0.0, 0.2};

std::string grid_csv() {
  std::string text = "theta_rad,omega_rad_s\n";
  for (double theta : kGridTheta) {
    for (double omega : kGridOmega) {
      text +=
          doorbench::format_csv_number(theta) + "," + doorbench::format_csv_number(omega) + "\n";
    }
  }
  return text;
}

// The value of `name` at grid point (theta, omega) in a parsed `model torque` output.
double value_at(const doorbench::CsvTable& table, const std::string& name, double theta,
                double omega) {
  const auto column = table.find_column(name);
  REQUIRE(column);
  const std::vector<double>& thetas = table.columns[*table.find_column("theta_rad")];
  const std::vector<double>& omegas = table.columns[*table.find_column("omega_rad_s")];
  for (std::size_t row = 0; row < table.row_count(); ++row) {
    if (thetas[row] == theta && omegas[row] == omega) return table.columns[*column][row];
  }
  FAIL("no row for theta " << theta << ", omega " << omega);
  return 0.0;
}

// Checks a run written by `simulate --hand open-close` (or the demo): the exchange format,
// 1 kHz from t = 0, the columns, and that the hand opened the door to about 80° and shut it.
void check_hand_run(const doorbench::Recording& run, ModelKind kind, double duration_s) {
  INFO(model_name(kind) << " model, " << duration_s << " s run");
  REQUIRE(run.handle_radius_m);
  CHECK(*run.handle_radius_m == 0.58);
  REQUIRE(run.sample_rate_hz);
  CHECK_THAT(*run.sample_rate_hz, WithinRel(1000.0, 1e-9));

  const auto samples = static_cast<std::size_t>(std::llround(duration_s * 1000.0)) + 1;
  REQUIRE(run.size() == samples);
  for (std::size_t i = 0; i < samples; ++i) {
    if (run.time_s[i] != static_cast<double>(i) / 1000.0) {
      FAIL("time_s[" << i << "] = " << run.time_s[i] << ", expected " << i << " ms");
    }
  }
  REQUIRE(run.force_N.size() == samples);
  REQUIRE(run.angle_rad);
  REQUIRE(run.rate_rad_s);
  REQUIRE(run.stroke);
  CHECK(run.stroke->front() == 0);
  CHECK(run.stroke->back() == 0);
  CHECK(std::find(run.stroke->begin(), run.stroke->end(), 1) != run.stroke->end());
  CHECK(std::find(run.stroke->begin(), run.stroke->end(), 2) != run.stroke->end());

  std::vector<std::string> expected_extra = {"tau_u_Nm", "tau_Nm"};
  for (const std::string& term : term_names(kind)) expected_extra.push_back("tau_" + term + "_Nm");
  REQUIRE(run.extra_names == expected_extra);

  // τ_u = r_h F_u, and τ_m is the sum of its terms.
  const std::vector<double>& tau_u = run.extra_columns[0];
  const std::vector<double>& tau_m = run.extra_columns[1];
  for (std::size_t i = 0; i < samples; ++i) {
    const double expected_tau_u = 0.58 * run.force_N[i];
    if (std::abs(tau_u[i] - expected_tau_u) > 1e-12 * (1.0 + std::abs(expected_tau_u))) {
      FAIL("row " << i << ": tau_u_Nm " << tau_u[i] << " is not 0.58 * force_N " << run.force_N[i]);
    }
    double sum = 0.0;
    double magnitude = 0.0;
    for (std::size_t term = 2; term < run.extra_columns.size(); ++term) {
      sum += run.extra_columns[term][i];
      magnitude += std::abs(run.extra_columns[term][i]);
    }
    if (std::abs(tau_m[i] - sum) > 1e-12 * (1.0 + magnitude)) {
      FAIL("row " << i << ": tau_Nm " << tau_m[i] << " is not the sum of the terms " << sum);
    }
  }

  const std::vector<double>& angle = *run.angle_rad;
  const double largest = *std::max_element(angle.begin(), angle.end());
  CHECK(largest > 1.2);                  // opened towards the 80° (1.396 rad) target
  CHECK(largest < 1.5708);               // short of the fully open stop
  CHECK(std::abs(angle.back()) < 0.02);  // and shut again
  CHECK(angle.front() == 0.0);
}

}  // namespace

// =========================================================================================
// 1. Help

TEST_CASE("CLI: --help for the command and every verb exits 0 and lists the options", "[cli]") {
  ScratchDir scratch;
  struct HelpCase {
    std::vector<std::string> verb;
    std::vector<std::string> mentions;
  };
  const std::vector<HelpCase> cases = {
      {{},
       {"Usage:", "--help", "--version", "model", "simulate", "demo", "record", "info", "export",
        "import"}},
      {{"model"}, {"Usage:", "model", "torque"}},
      {{"model", "torque"},
       {"Usage:", "model torque", "--model", "sensory", "physical", "--params", "--effects", "--in",
        "--out"}},
      {{"simulate"},
       {"Usage:", "simulate", "--model", "--params", "--effects", "--force", "--hand", "open-close",
        "--target-deg", "--duration-s", "--rate-hz", "--out"}},
      {{"demo"}, {"Usage:", "demo", "--out"}},
      {{"record"},
       {"Usage:", "record", "--rig", "--duration-s", "--out", "--operator", "--product",
        "--notes"}},
      {{"info"}, {"Usage:", "info", "SESSION"}},
      {{"export"}, {"Usage:", "export", "SESSION", "--csv"}},
      {{"import"}, {"Usage:", "import", "CSV", "--out", "--operator", "--product", "--notes"}},
      {{"fit"},
       {"Usage:", "fit", "DATA", "--model", "--params", "--effects", "--free", "--fixed",
        "--objective", "--folds", "--out"}},
      {{"loop"},
       {"Usage:", "loop", "DATA", "--model", "--params", "--folds", "--max-steps", "--out"}},
  };
  for (const HelpCase& help : cases) {
    std::vector<std::string> args = help.verb;
    args.push_back("--help");
    SECTION(describe(args)) {
      const RunResult result = run_doorbench(args, scratch);
      INFO("stdout: " << result.out << "\nstderr: " << result.err);
      CHECK(result.exit_code == 0);
      CHECK(result.err.empty());
      for (const std::string& text : help.mentions) CHECK_THAT(result.out, Contains(text));
    }
  }
}

TEST_CASE("CLI: --version prints the version and exits 0", "[cli]") {
  ScratchDir scratch;
  const RunResult result = run_doorbench({"--version"}, scratch);
  CHECK(result.exit_code == 0);
  CHECK_THAT(result.out, StartsWith("doorbench "));
  CHECK(result.err.empty());
}

// =========================================================================================
// 2. Usage errors: exit 2, one line on stderr

TEST_CASE("CLI: usage errors exit 2 with one line that names the problem", "[cli]") {
  ScratchDir scratch;
  const std::string grid = scratch.write("grid.csv", grid_csv()).string();
  const std::string out = (scratch / "out.csv").string();

  SECTION("no verb") {
    const RunResult result = run_doorbench({}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("subcommand"));
  }
  SECTION("unknown verb") {
    const RunResult result = run_doorbench({"bogus"}, scratch);
    require_usage_error(result);
  }
  SECTION("model without its subcommand") {
    const RunResult result = run_doorbench({"model"}, scratch);
    require_usage_error(result);
  }
  SECTION("model torque without --in") {
    const RunResult result = run_doorbench({"model", "torque", "--out", out}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("--in"));
    CHECK(!fs::exists(out));
  }
  SECTION("model torque without --out") {
    const RunResult result = run_doorbench({"model", "torque", "--in", grid}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("--out"));
  }
  SECTION("--model bogus") {
    const RunResult result =
        run_doorbench({"model", "torque", "--model", "bogus", "--in", grid, "--out", out}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("--model"));
    CHECK_THAT(result.err, Contains("bogus"));
    CHECK(!fs::exists(out));
  }
  SECTION("simulate with both --force and --hand") {
    const RunResult result =
        run_doorbench({"simulate", "--force", grid, "--hand", "open-close", "--out", out}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("--force"));
    CHECK_THAT(result.err, Contains("--hand"));
    CHECK(!fs::exists(out));
  }
  SECTION("simulate with neither --force nor --hand") {
    const RunResult result = run_doorbench({"simulate", "--out", out}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("exactly one of --force"));
    CHECK(!fs::exists(out));
  }
  SECTION("simulate --hand with an unknown hand") {
    const RunResult result = run_doorbench({"simulate", "--hand", "wave", "--out", out}, scratch);
    require_usage_error(result);
    CHECK_THAT(result.err, Contains("--hand"));
    CHECK_THAT(result.err, Contains("wave"));
  }
}

// Known bug: CLI11's "A subcommand is required" is reported for an unknown verb, so the
// message does not name it (see the report that came with this file).
TEST_CASE("CLI: an unknown verb is named in the message", "[cli]") {
  ScratchDir scratch;
  const RunResult result = run_doorbench({"bogus"}, scratch);
  require_usage_error(result);
  CHECK_THAT(result.err, Contains("bogus"));
}

// =========================================================================================
// 3. Failures: exit 1, one line naming the file, line and key

TEST_CASE("CLI: model torque failures exit 1 with one line naming the file and line and key",
          "[cli]") {
  ScratchDir scratch;
  const std::string grid = scratch.write("grid.csv", grid_csv()).string();
  const std::string out = (scratch / "out.csv").string();
  auto torque = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {"model", "torque"};
    args.insert(args.end(), extra.begin(), extra.end());
    if (std::find(extra.begin(), extra.end(), "--in") == extra.end()) {
      args.insert(args.end(), {"--in", grid});
    }
    args.insert(args.end(), {"--out", out});
    return run_doorbench(args, scratch);
  };

  SECTION("grid file missing") {
    const std::string missing = (scratch / "no-such-grid.csv").string();
    const RunResult result = torque({"--in", missing});
    require_failure(result);
    CHECK(result.err == "doorbench: " + missing + ": cannot open for reading\n");
  }
  SECTION("grid without omega_rad_s") {
    // A metadata line first, so the header is line 2.
    const std::string path =
        scratch.write("no-omega.csv", "# source: hand-made\ntheta_rad,omega\n0.1,0\n").string();
    const RunResult result = torque({"--in", path});
    require_failure(result);
    CHECK(result.err == "doorbench: " + path + ":2: header lacks required column omega_rad_s\n");
  }
  SECTION("grid without theta_rad") {
    const std::string path =
        scratch.write("no-theta.csv", "angle_rad,omega_rad_s\n0.1,0\n").string();
    const RunResult result = torque({"--in", path});
    require_failure(result);
    CHECK(result.err == "doorbench: " + path + ":1: header lacks required column theta_rad\n");
  }
  SECTION("grid with a non-numeric cell") {
    const std::string path =
        scratch.write("text-cell.csv", "theta_rad,omega_rad_s\n0,0\n\n0.1,abc\n").string();
    const RunResult result = torque({"--in", path});
    require_failure(result);
    // Line 4: the blank line counts.
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ":4: "));
    CHECK_THAT(result.err, Contains("omega_rad_s"));
    CHECK_THAT(result.err, Contains("'abc' is not a number"));
  }
  SECTION("parameter file missing") {
    const std::string missing = (scratch / "no-such-door.json").string();
    const RunResult result = torque({"--params", missing});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + missing + ": "));
  }
  SECTION("parameter file with an unknown top-level key") {
    auto root = reference_json();
    root["colour"] = "red";
    const std::string path = scratch.write("door.json", root.dump(2)).string();
    const RunResult result = torque({"--params", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("colour"));
    CHECK_THAT(result.err, Contains("unknown key"));
  }
  SECTION("parameter file with an unknown parameter") {
    auto root = reference_json();
    root["sensory"]["wobble"] = {{"value", 1.0}, {"bounds", {0.0, 2.0}}};
    const std::string path = scratch.write("door.json", root.dump(2)).string();
    const RunResult result = torque({"--params", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("sensory.wobble"));
    CHECK_THAT(result.err, Contains("unknown parameter"));
  }
  SECTION("parameter file that is not JSON") {
    const std::string path = scratch.write("door.json", "{\"handle_radius_m\": 0.58,\n").string();
    const RunResult result = torque({"--params", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("line 2"));
  }
  SECTION("parameter file breaking a constraint: theta1 < theta0") {
    auto root = reference_json();
    root["sensory"]["theta1"]["value"] = 0.005;  // theta0 is 0.00698
    const std::string path = scratch.write("door.json", root.dump(2)).string();
    const RunResult result = torque({"--params", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("theta0 = 0.00698"));
    CHECK_THAT(result.err, Contains("0 < theta0 < theta1"));
    CHECK_THAT(result.err, Contains("theta1 = 0.005"));
  }
  SECTION("parameter file breaking a physical constraint, with --model physical") {
    auto root = reference_json();
    root["physical"]["m_d"]["value"] = -1.0;
    const std::string path = scratch.write("door.json", root.dump(2)).string();
    const RunResult result = torque({"--model", "physical", "--params", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("m_d"));
  }
  SECTION("effects file with an unknown effect") {
    const std::string path = scratch.write("effects.json", R"({"wobble": {"x": 1}})").string();
    const RunResult result = torque({"--effects", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("wobble"));
    CHECK_THAT(result.err, Contains("unknown effect"));
  }
  SECTION("effects file with an unknown parameter of a known effect") {
    const std::string path =
        scratch.write("effects.json", R"({"stribeck": {"d_s": 3, "w_s": 0.05, "q": 1}})").string();
    const RunResult result = torque({"--effects", path});
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + path + ": "));
    CHECK_THAT(result.err, Contains("stribeck.q"));
  }
  SECTION("output folder missing") {
    const std::string bad_out = (scratch / "no-such-folder" / "out.csv").string();
    const RunResult result =
        run_doorbench({"model", "torque", "--in", grid, "--out", bad_out}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, Contains(bad_out));
  }
  CHECK(!fs::exists(out));
}

// =========================================================================================
// 4. model torque on the reference door

TEST_CASE("CLI: model torque on the reference door gives the spec's terms and values", "[cli]") {
  ScratchDir scratch;
  const std::string grid = scratch.write("grid.csv", grid_csv()).string();
  const std::size_t grid_points = kGridTheta.size() * kGridOmega.size();

  for (const ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const std::string name = model_name(kind);
    SECTION(name) {
      const std::string out = (scratch / (name + "-torque.csv")).string();
      const RunResult result =
          run_doorbench({"model", "torque", "--model", name, "--in", grid, "--out", out}, scratch);
      require_success(result);
      CHECK(result.out.empty());
      CHECK(result.err.empty());

      const doorbench::CsvTable table = doorbench::parse_csv_table(read_file(out), out);
      std::vector<std::string> expected_columns = {"theta_rad", "omega_rad_s", "tau_Nm"};
      for (const std::string& term : term_names(kind)) {
        expected_columns.push_back("tau_" + term + "_Nm");
      }
      REQUIRE(table.column_names == expected_columns);
      REQUIRE(table.row_count() == grid_points);
      CHECK(table.metadata_value("handle_radius_m") == std::optional<std::string>("0.58"));

      // The grid comes back as given, and each row equals the in-process model bit for bit.
      const doorbench::DoorModel model = doorbench::reference_model(kind);
      REQUIRE(model.term_count() == static_cast<int>(term_names(kind).size()));
      std::array<double, doorbench::DoorModel::kMaxTerms> terms{};
      std::size_t row = 0;
      for (double theta : kGridTheta) {
        for (double omega : kGridOmega) {
          INFO("row " << row << ": theta " << theta << ", omega " << omega);
          REQUIRE(same_bits(table.columns[0][row], theta));
          REQUIRE(same_bits(table.columns[1][row], omega));
          const double total = model.torque_Nm(theta, omega, terms);
          CHECK(same_bits(table.columns[2][row], total));
          CHECK(same_bits(table.columns[2][row], model.torque_Nm(theta, omega)));
          double sum = 0.0;
          double magnitude = 0.0;
          for (int term = 0; term < model.term_count(); ++term) {
            const double value = table.columns[3 + term][row];
            INFO("term " << model.term_name(term));
            CHECK(same_bits(value, terms[term]));
            sum += value;
            magnitude += std::abs(value);
          }
          // τ_m is the sum of the terms (to rounding).
          CHECK(std::abs(table.columns[2][row] - sum) <= 1e-12 * (1.0 + magnitude));
          ++row;
        }
      }

      // Values worked out by hand from the spec (door-models.md §2, §3) and the reference
      // door's parameters.
      auto at = [&](const std::string& column, double theta, double omega) {
        return value_at(table, column, theta, omega);
      };
      if (kind == ModelKind::kSensory) {
        // θ = 0.02 lies between θ0 and θ1, far from every switch (β = 3000): τ_o alone,
        // friction −tanh(0)·(...) = 0, no snap or latch (ω = 0, θ < θ2), no stop.
        const double unlatch = -(40.0 * 0.02 + 1054.0 * (0.02 - 0.00698));
        CHECK_THAT(at("tau_unlatch_Nm", 0.02, 0.0), WithinRel(unlatch, 1e-9));
        CHECK(at("tau_friction_Nm", 0.02, 0.0) == 0.0);
        CHECK(at("tau_snap_Nm", 0.02, 0.0) == 0.0);
        CHECK(at("tau_stops_Nm", 0.02, 0.0) == 0.0);
        CHECK_THAT(at("tau_Nm", 0.02, 0.0), WithinRel(unlatch, 1e-9));
        // Snap zone θ1 < 0.03 < θ2: negative damping + c ω W(θ; θ1, θ2, β), W ≈ 1 − 4e-6.
        const double snap_window = 0.5 * (1.0 + std::tanh(3000.0 * (0.03 - 0.02793))) -
                                   0.5 * (1.0 + std::tanh(3000.0 * (0.03 - 0.0384)));
        CHECK_THAT(at("tau_snap_Nm", 0.03, 0.2), WithinRel(3.0 * 0.2 * snap_window, 1e-9));
        CHECK_THAT(at("tau_snap_Nm", 0.03, 0.2), WithinRel(3.0 * 0.2, 1e-4));
        // Latching zone θ2 < 0.05 < θ3: + k_lock (θ3 − θ).
        CHECK_THAT(at("tau_latch_Nm", 0.05, 0.0), WithinRel(767.0 * (0.06109 - 0.05), 1e-9));
        // Free movement at θ = 0.5: −tanh(s ω) (d1 − d2 S̄(θ; θ4, β_f)).
        const double closed_share = 0.5 * (1.0 - std::tanh(10.0 * (0.5 - 0.6109)));
        const double friction = -std::tanh(25.0 * 0.2) * (2.6 - 1.3 * closed_share);
        CHECK_THAT(at("tau_friction_Nm", 0.5, 0.2), WithinRel(friction, 1e-9));
        CHECK_THAT(at("tau_Nm", 0.5, 0.2), WithinRel(friction, 1e-9));
        // End stops: the cabinet at θ < 0, the open stop past θ_max = 1.5708.
        CHECK_THAT(at("tau_stops_Nm", -0.01, 0.2), WithinRel(-(5000.0 * -0.01 + 20.0 * 0.2), 1e-9));
        CHECK_THAT(at("tau_stops_Nm", 1.6, 0.0), WithinRel(-5000.0 * (1.6 - 1.5708), 1e-9));
        CHECK(at("tau_stops_Nm", 1.5, -0.5) == 0.0);
      } else {
        // Gravity m_d g l_c sin θ.
        CHECK_THAT(at("tau_gravity_Nm", 0.5, 0.0),
                   WithinRel(7.5 * 9.80665 * 0.3 * std::sin(0.5), 1e-9));
        CHECK_THAT(at("tau_gravity_Nm", 1.0, 0.2),
                   WithinRel(7.5 * 9.80665 * 0.3 * std::sin(1.0), 1e-9));
        // Hinge friction −T_h tanh(ω / w_f) − b_h ω.
        CHECK_THAT(at("tau_hinge_friction_Nm", 0.5, 0.2),
                   WithinRel(-0.6 * std::tanh(0.2 / 0.02) - 0.05 * 0.2, 1e-9));
        CHECK(at("tau_hinge_friction_Nm", 0.5, 0.0) == 0.0);
        // Seal + k_seal (θ_seal − θ) below θ_seal = 0.01, 0 beyond.
        CHECK_THAT(at("tau_seal_Nm", 0.003, 0.0), WithinRel(150.0 * (0.01 - 0.003), 1e-9));
        CHECK(at("tau_seal_Nm", 0.02, 0.0) == 0.0);
        // The latch is out of reach at θ = 0.5 (r_l θ = 0.3 m, x2 ≈ 0.018 m).
        CHECK(std::abs(at("tau_latch_Nm", 0.5, 0.0)) < 1e-12);
        // Balancing spring (§3): A = (0, −0.35), B = B_u (sin θ, cos θ), B_u = −0.05.
        const double theta = 0.5;
        const double b_x = -0.05 * std::sin(theta);
        const double b_y = -0.05 * std::cos(theta);
        const double d_x = 0.0 - b_x;
        const double d_y = -0.35 - b_y;
        const double length = std::hypot(d_x, d_y);
        const double tension = 250.0 + 2450.0 * (length - 0.3);
        const double spring = -(b_x * tension * d_y / length - b_y * tension * d_x / length);
        CHECK_THAT(at("tau_spring_Nm", 0.5, 0.0), WithinRel(spring, 1e-9));
        // Guide friction −mu_g T tanh(ω / w_f).
        CHECK_THAT(at("tau_guide_friction_Nm", 0.5, 0.2),
                   WithinRel(-0.006 * tension * std::tanh(0.2 / 0.02), 1e-9));
        // End stops, shared with the sensory model.
        CHECK_THAT(at("tau_stops_Nm", -0.01, 0.2), WithinRel(-(5000.0 * -0.01 + 20.0 * 0.2), 1e-9));
      }
    }
  }
}

TEST_CASE("CLI: model torque with a parameter file and an effects file", "[cli]") {
  ScratchDir scratch;
  const std::string grid = scratch.write("grid.csv", grid_csv()).string();
  auto root = reference_json();
  root["sensory"]["d1"]["value"] = 3.0;
  const std::string params = scratch.write("door.json", root.dump(2)).string();
  const std::string effects =
      scratch.write("effects.json", R"({"viscous_damping": {"b": 0.5}})").string();
  const std::string out = (scratch / "out.csv").string();

  const RunResult result = run_doorbench(
      {"model", "torque", "--params", params, "--effects", effects, "--in", grid, "--out", out},
      scratch);
  require_success(result);
  const doorbench::CsvTable table = doorbench::parse_csv_table(read_file(out), out);
  std::vector<std::string> expected_columns = {"theta_rad", "omega_rad_s", "tau_Nm"};
  for (const std::string& term : kSensoryTerms) expected_columns.push_back("tau_" + term + "_Nm");
  expected_columns.push_back("tau_viscous_damping_Nm");
  REQUIRE(table.column_names == expected_columns);
  CHECK(table.metadata_value("params") == std::optional<std::string>(params));

  // − b ω, and the friction with d1 = 3 at θ = 1.0 (S̄(1.0; θ4, β_f) ≈ 4e-4).
  CHECK_THAT(value_at(table, "tau_viscous_damping_Nm", 0.5, 0.2), WithinRel(-0.5 * 0.2, 1e-12));
  const doorbench::DoorModel model = doorbench::load_model(ModelKind::kSensory, params, effects);
  std::array<double, doorbench::DoorModel::kMaxTerms> terms{};
  const double total = model.torque_Nm(1.0, -0.5, terms);
  CHECK(same_bits(value_at(table, "tau_Nm", 1.0, -0.5), total));
  CHECK(same_bits(value_at(table, "tau_friction_Nm", 1.0, -0.5), terms[3]));
  const double closed_share = 0.5 * (1.0 - std::tanh(10.0 * (1.0 - 0.6109)));
  CHECK_THAT(terms[3], WithinRel(std::tanh(25.0 * 0.5) * (3.0 - 1.3 * closed_share), 1e-9));
}

// =========================================================================================
// 5. and 6. simulate

// Known bug: the virtual hand needs hold_s + release_s (0.5 s) to fit in the final rest
// (10% of the run), so every --duration-s below 5 s fails with exit 1, although the
// option accepts 0.5 to 3600 s (see the report that came with this file).
TEST_CASE("CLI: simulate --hand open-close --duration-s 4", "[cli]") {
  ScratchDir scratch;
  const std::string out = (scratch / "run.csv").string();
  const RunResult result = run_doorbench(
      {"simulate", "--hand", "open-close", "--duration-s", "4", "--out", out}, scratch);
  require_success(result);
  check_hand_run(doorbench::read_recording_csv(out), ModelKind::kSensory, 4.0);
}

TEST_CASE("CLI: simulate --hand open-close opens the door to about 80 deg and shuts it", "[cli]") {
  ScratchDir scratch;
  for (const ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const std::string name = model_name(kind);
    SECTION(name) {
      const std::string out = (scratch / (name + "-run.csv")).string();
      // 5 s: the shortest run the virtual hand accepts with its default hold and release.
      const RunResult result = run_doorbench(
          {"simulate", "--model", name, "--hand", "open-close", "--duration-s", "5", "--out", out},
          scratch);
      require_success(result);
      CHECK(result.out.empty());
      // One progress line on stderr.
      // A success reports on one stderr line, without the "doorbench: " of an error.
      CHECK_THAT(result.err, StartsWith("wrote 5001 samples to " + out));
      CHECK(std::count(result.err.begin(), result.err.end(), '\n') == 1);

      const doorbench::Recording run = doorbench::read_recording_csv(out);
      check_hand_run(run, kind, 5.0);
      // The command line that made it is recorded.
      bool has_source = false;
      for (const auto& [key, value] : run.metadata) {
        if (key == "source") {
          has_source = true;
          CHECK_THAT(value, Contains("simulate --model " + name));
          CHECK_THAT(value, Contains("--hand open-close"));
        }
      }
      CHECK(has_source);
    }
  }
}

TEST_CASE("CLI: simulate --target-deg and --rate-hz shape the virtual hand's run", "[cli]") {
  ScratchDir scratch;
  const std::string out = (scratch / "run.csv").string();
  const RunResult result = run_doorbench({"simulate", "--hand", "open-close", "--target-deg", "45",
                                          "--duration-s", "6", "--rate-hz", "200", "--out", out},
                                         scratch);
  require_success(result);
  const doorbench::Recording run = doorbench::read_recording_csv(out);
  REQUIRE(run.size() == 6 * 200 + 1);
  CHECK(run.time_s[1] == 1.0 / 200.0);
  CHECK(run.time_s.back() == 6.0);
  REQUIRE(run.sample_rate_hz);
  CHECK_THAT(*run.sample_rate_hz, WithinRel(200.0, 1e-9));
  const double largest = *std::max_element(run.angle_rad->begin(), run.angle_rad->end());
  const double target = 45.0 * doorbench::kRadPerDeg;
  CHECK(largest > target - 0.1);
  CHECK(largest < target + 0.1);
  CHECK(std::abs(run.angle_rad->back()) < 0.02);
}

TEST_CASE("CLI: simulate --force replays a run and rejects another handle radius", "[cli]") {
  ScratchDir scratch;
  const std::string first = (scratch / "hand.csv").string();
  require_success(run_doorbench(
      {"simulate", "--hand", "open-close", "--duration-s", "5", "--out", first}, scratch));
  const doorbench::Recording hand_run = doorbench::read_recording_csv(first);

  SECTION("the same door under the recorded force") {
    const std::string replay = (scratch / "replay.csv").string();
    const RunResult result =
        run_doorbench({"simulate", "--force", first, "--out", replay}, scratch);
    require_success(result);
    CHECK(result.out.empty());
    const doorbench::Recording run = doorbench::read_recording_csv(replay);
    REQUIRE(run.time_s == hand_run.time_s);
    CHECK(run.force_N == hand_run.force_N);
    REQUIRE(run.handle_radius_m);
    CHECK(*run.handle_radius_m == 0.58);
    REQUIRE(run.stroke);
    CHECK(*run.stroke == *hand_run.stroke);
    std::vector<std::string> expected_extra = {"tau_u_Nm", "tau_Nm"};
    for (const std::string& term : kSensoryTerms) expected_extra.push_back("tau_" + term + "_Nm");
    CHECK(run.extra_names == expected_extra);
    // Same model, same force, same start, no noise: the replay follows the original.
    double largest_difference = 0.0;
    for (std::size_t i = 0; i < run.size(); ++i) {
      largest_difference =
          std::max(largest_difference, std::abs((*run.angle_rad)[i] - (*hand_run.angle_rad)[i]));
    }
    CHECK(largest_difference < 0.02);
    for (const auto& [key, value] : run.metadata) {
      if (key == "source") CHECK_THAT(value, Contains("--force " + first));
    }
  }
  SECTION("a recording with another handle radius") {
    std::string text = read_file(first);
    const std::string original = "# handle_radius_m: 0.58\n";
    const auto position = text.find(original);
    REQUIRE(position != std::string::npos);
    text.replace(position, original.size(), "# handle_radius_m: 0.31\n");
    const std::string other = scratch.write("bench-0.31.csv", text).string();
    const std::string replay = (scratch / "replay.csv").string();
    const RunResult result =
        run_doorbench({"simulate", "--force", other, "--out", replay}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + other + ": "));
    CHECK_THAT(result.err, Contains("handle_radius_m"));
    CHECK_THAT(result.err, Contains("0.31"));
    CHECK_THAT(result.err, Contains("0.58"));
    CHECK(!fs::exists(replay));
  }
  SECTION("a recording that breaks the exchange format") {
    const std::string bad = scratch
                                .write("bad.csv",
                                       "# handle_radius_m: 0.58\n"
                                       "time_s,force_N,angle_rad\n"
                                       "0,0,0\n"
                                       "0,1,0\n")
                                .string();
    const std::string replay = (scratch / "replay.csv").string();
    const RunResult result = run_doorbench({"simulate", "--force", bad, "--out", replay}, scratch);
    require_failure(result);
    CHECK(result.err == "doorbench: " + bad + ":4: time_s 0 is not after the previous row's 0\n");
    CHECK(!fs::exists(replay));
  }
}

// =========================================================================================
// 7. demo

namespace {

// Every number after `label` in `text`, in order.
std::vector<double> numbers_after(const std::string& text, const std::string& label) {
  std::vector<double> numbers;
  for (auto position = text.find(label); position != std::string::npos;
       position = text.find(label, position + label.size())) {
    std::istringstream rest(text.substr(position + label.size()));
    double value = 0.0;
    if (rest >> value) numbers.push_back(value);
  }
  return numbers;
}

}  // namespace

TEST_CASE("CLI: demo summarizes both models and writes their runs", "[cli]") {
  ScratchDir scratch;
  const fs::path dir = scratch / "demo out";  // a space in the path, passed as one argument
  const RunResult result = run_doorbench({"demo", "--out", dir.string()}, scratch);
  require_success(result);
  CHECK(result.err.empty());
  INFO("stdout: " << result.out);

  CHECK_THAT(result.out, Contains("sensory model ("));
  CHECK_THAT(result.out, Contains("physical model ("));
  CHECK(result.out.find("sensory model (") < result.out.find("physical model ("));
  // The loop closed on a recording with an undeclared gravity imbalance: the table of
  // steps names it, with the error before and after, and the report is on disk.
  CHECK_THAT(result.out, Contains("closing the loop"));
  CHECK_THAT(result.out, Contains("| step | effect | parameters |"));
  CHECK_THAT(result.out, Contains("| 1 | gravity_imbalance | gravity_imbalance.g1 = "));
  CHECK(fs::exists(dir / "loop" / "report.md"));
  CHECK(fs::exists(dir / "loop" / "result.json"));

  // The haptic playback of the fitted door, fitted back; the tuned variant and its specification.
  CHECK_THAT(result.out,
             Contains("haptic playback: the fitted door on the simulated HapticMaster"));
  CHECK_THAT(result.out, Contains("fitted back (6 strokes, from the reference door)"));
  CHECK_THAT(result.out, Contains("the design specification: the AS-IS physical door"));
  CHECK_THAT(result.out, Contains("played vs specified"));
  // The specification names what was played: k_l and F_l0 x0.7 from the commanded torque,
  // J_d x1.2 from the motion (within 5 %: the device's own dynamics are in it).
  for (const auto& [name, tolerance] :
       std::vector<std::pair<std::string, double>>{{"k_l", 0.5}, {"F_l0", 0.5}, {"J_d", 5.0}}) {
    const std::string line_start = "    " + name + std::string(7 - name.size(), ' ') + "AS-IS";
    const auto line = result.out.find(line_start);
    REQUIRE(line != std::string::npos);
    const auto end = result.out.find('\n', line);
    const std::string text = result.out.substr(line, end - line);
    const std::vector<double> percent = numbers_after(text, "(");
    INFO(text);
    REQUIRE(percent.size() == 1);
    CHECK(std::abs(percent.front()) <= tolerance);
  }
  CHECK(fs::exists(dir / "haptic-playback.h5"));
  CHECK(fs::exists(dir / "tobe-tuned.h5"));
  CHECK(fs::exists(dir / "spec" / "spec.json"));
  CHECK(fs::exists(dir / "spec" / "spec.html"));

  // The two models' summaries come first (the specification's felt quantities follow).
  std::vector<double> unlatch = numbers_after(result.out, "peak force to unlatch");
  REQUIRE(unlatch.size() >= 2);
  unlatch.resize(2);
  for (double force : unlatch) {
    CHECK(force > 10.0);
    CHECK(force < 100.0);
  }
  std::vector<double> latch = numbers_after(result.out, "peak force to latch");
  REQUIRE(latch.size() >= 2);
  latch.resize(2);
  for (double force : latch) {
    CHECK(force > 5.0);
    CHECK(force < 100.0);
  }
  std::vector<double> friction = numbers_after(result.out, "friction in free movement");
  REQUIRE(friction.size() >= 2);
  friction.resize(2);
  for (double force : friction) {
    CHECK(force > 1.0);
    CHECK(force < 10.0);
  }

  for (const ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const fs::path run_path = dir / (model_name(kind) + "-open-close.csv");
    INFO(run_path);
    REQUIRE(fs::is_regular_file(run_path));
    CHECK_THAT(result.out, Contains(run_path.string()));
    check_hand_run(doorbench::read_recording_csv(run_path), kind, 10.0);
    // The parameter file beside it loads back as the reference door.
    const fs::path params_path = dir / (model_name(kind) + "-params.json");
    REQUIRE(fs::is_regular_file(params_path));
    const doorbench::DoorModel loaded = doorbench::load_model(kind, params_path, {});
    const doorbench::DoorModel reference = doorbench::reference_model(kind);
    CHECK(std::equal(loaded.parameter_values().begin(), loaded.parameter_values().end(),
                     reference.parameter_values().begin(), reference.parameter_values().end()));
  }
}

TEST_CASE("CLI: demo without --out writes doorbench-demo/ in the working folder", "[cli]") {
  ScratchDir scratch;
  const RunResult result = run_doorbench({"demo"}, scratch, scratch.path());
  require_success(result);
  CHECK(fs::is_regular_file(scratch / "doorbench-demo" / "sensory-open-close.csv"));
  CHECK(fs::is_regular_file(scratch / "doorbench-demo" / "physical-open-close.csv"));
}

TEST_CASE("CLI: demo fails with exit 1 when its folder cannot be made", "[cli]") {
  ScratchDir scratch;
  const std::string file = scratch.write("a-file", "not a folder").string();
  const RunResult result = run_doorbench({"demo", "--out", file}, scratch);
  require_failure(result);
  CHECK_THAT(result.err, Contains(file));
}

// =========================================================================================
// 8. Sessions: record, info, export, import

namespace {

std::string shipped_rig_text() {
  const fs::path rig = fs::path(DOORBENCH_SOURCE_DIR) / "rigs" / "simulated-dishwasher.toml";
  REQUIRE(fs::is_regular_file(rig));
  return read_file(rig);
}

// `text` with its one occurrence of `from` replaced by `to`.
std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto position = text.find(from);
  REQUIRE(position != std::string::npos);
  REQUIRE(text.find(from, position + 1) == std::string::npos);
  text.replace(position, from.size(), to);
  return text;
}

// `text` with every occurrence of `from` replaced by `to`.
std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (auto position = text.find(from); position != std::string::npos;
       position = text.find(from, position + to.size())) {
    text.replace(position, from.size(), to);
  }
  return text;
}

// The line (from 1) of `text` on which `needle` starts.
int line_of(const std::string& text, const std::string& needle) {
  const auto position = text.find(needle);
  REQUIRE(position != std::string::npos);
  return 1 + static_cast<int>(
                 std::count(text.begin(), text.begin() + static_cast<long>(position), '\n'));
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> words_of(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream in(line);
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

// The indented lines that follow the line starting with `heading`.
std::vector<std::string> section_lines(const std::string& text, const std::string& heading) {
  const std::vector<std::string> lines = lines_of(text);
  std::vector<std::string> section;
  auto line = std::find_if(lines.begin(), lines.end(),
                           [&](const std::string& l) { return l.rfind(heading, 0) == 0; });
  REQUIRE(line != lines.end());
  for (++line; line != lines.end() && line->rfind(" ", 0) == 0; ++line) section.push_back(*line);
  return section;
}

// A successful `record`: nothing on stdout; on stderr status lines, none of them an error, the
// last one naming the session.
void require_recorded(const RunResult& result, const std::string& session) {
  require_success(result);
  INFO("stdout: " << result.out << "\nstderr: " << result.err);
  CHECK(result.out.empty());
  REQUIRE_THAT(result.err, EndsWith("\n"));
  const std::vector<std::string> lines = lines_of(result.err);
  REQUIRE(!lines.empty());
  for (const std::string& line : lines) CHECK_THAT(line, !StartsWith("doorbench: "));
  CHECK_THAT(lines.back(), StartsWith("wrote " + session));
}

// The shipped rig with a 1.5 s hand cycle: 3 s hold two openings and two closings.
fs::path quick_cycle_rig(const ScratchDir& scratch) {
  return scratch.write(
      "quick-cycle.toml",
      replace_once(shipped_rig_text(), "cycle_duration_s = 6.0", "cycle_duration_s = 1.5"));
}

// A 3 s session recorded on quick_cycle_rig().
std::string record_quick_session(const ScratchDir& scratch) {
  const std::string rig = quick_cycle_rig(scratch).string();
  const std::string session = (scratch / "quick.h5").string();
  const RunResult result =
      run_doorbench({"record", "--rig", rig, "--duration-s", "3", "--out", session}, scratch);
  require_recorded(result, session);
  return session;
}

// The lines of the CSV exchange format for `rows` rows at 1 kHz: rows 3, 4, ... (after a
// metadata line and the header), so that row r is on line r + 3.
std::vector<std::string> csv_rows(int rows) {
  std::vector<std::string> lines;
  for (int row = 0; row < rows; ++row) {
    const int stroke = row >= 3 && row < 8 ? 1 : 0;
    lines.push_back(doorbench::format_csv_number(row / 1000.0) + "," +
                    doorbench::format_csv_number(0.5 * row) + "," +
                    doorbench::format_csv_number(0.01 * row) + "," + std::to_string(stroke));
  }
  return lines;
}

std::string csv_text(const std::vector<std::string>& rows) {
  std::string text = "# handle_radius_m: 0.58\ntime_s,force_N,rate_rad_s,stroke\n";
  for (const std::string& row : rows) text += row + "\n";
  return text;
}

}  // namespace

TEST_CASE("CLI: record with the built-in rig writes a session of force, angle and rate",
          "[cli][session]") {
  ScratchDir scratch;
  const std::string session = (scratch / "first session.h5").string();
  const RunResult result =
      run_doorbench({"record", "--duration-s", "2", "--out", session, "--operator", "Zoë Weber",
                     "--product", "DW-60 #17", "--notes", "first try, lab 2; door cold"},
                    scratch);
  require_recorded(result, session);

  const doorbench::SessionReader reader(session);
  const std::vector<doorbench::ChannelInfo>& channels = reader.channels();
  const std::array<std::array<std::string, 3>, 3> expected = {{{"force", "load_cell", "N"},
                                                               {"angle", "inclinometer", "rad"},
                                                               {"rate", "gyroscope", "rad/s"}}};
  REQUIRE(channels.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    INFO("channel " << i);
    CHECK(channels[i].name == expected[i][0]);
    CHECK(channels[i].sensor_kind == expected[i][1]);
    CHECK(channels[i].unit == expected[i][2]);
    CHECK(channels[i].sample_rate_hz == 1000.0);
    CHECK(reader.sample_count(channels[i].name) == 2000);
    CHECK(!channels[i].calibration_id.empty());
  }

  const doorbench::SessionMetadata& metadata = reader.metadata();
  CHECK(metadata.operator_name == "Zoë Weber");
  CHECK(metadata.product_id == "DW-60 #17");
  CHECK(metadata.notes == "first try, lab 2; door cold");
  CHECK(metadata.rig_name == "simulated-dishwasher");
  CHECK(metadata.rig_definition == shipped_rig_text());
  CHECK_THAT(metadata.software_version, StartsWith("doorbench "));
  // The UTC time of session time 0, to the nanosecond: 2026-11-21T10:30:00.123456789Z.
  CHECK(metadata.start_time_utc.size() == 30);
  CHECK_THAT(metadata.start_time_utc, EndsWith("Z"));
  CHECK(reader.read_group_attribute("clock", "origin_utc") == metadata.start_time_utc);

  // Every channel's calibration record is in the session, in full.
  const auto records = reader.calibrations();
  REQUIRE(records.size() == 3);
  for (const doorbench::ChannelInfo& channel : channels) {
    const auto record = std::find_if(records.begin(), records.end(),
                                     [&](const auto& r) { return r.id == channel.calibration_id; });
    REQUIRE(record != records.end());
    CHECK(record->unit == channel.unit);
  }

  // One software trigger started it.
  const std::vector<doorbench::SessionEvent> events = reader.events();
  CHECK(std::count_if(events.begin(), events.end(),
                      [](const auto& e) { return e.kind == "trigger"; }) == 1);

  // The simulated bench's truth, one value per scan.
  CHECK(reader.group_datasets("truth") ==
        std::vector<std::string>{"force_N", "omega_rad_s", "theta_rad", "time_s"});
  for (const std::string& name : reader.group_datasets("truth")) {
    INFO("truth/" << name);
    CHECK(reader.read_group_dataset("truth", name).size() == 2000);
  }
  CHECK(std::stod(reader.read_group_attribute("truth", "handle_radius_m")) == 0.58);
  const std::vector<double> truth_force = reader.read_group_dataset("truth", "force_N");
  CHECK(*std::max_element(truth_force.begin(), truth_force.end()) > 5.0);  // the hand pushed
}

TEST_CASE("CLI: record never overwrites a session", "[cli][session]") {
  ScratchDir scratch;
  const std::string session = (scratch / "s.h5").string();
  require_recorded(run_doorbench({"record", "--duration-s", "2", "--out", session}, scratch),
                   session);
  const std::string before = read_file(session);

  const RunResult again = run_doorbench(
      {"record", "--duration-s", "3", "--out", session, "--operator", "someone else"}, scratch);
  CHECK(again.exit_code == 2);  // refused before recording (docs/output-files.md)
  CHECK(again.err == "doorbench: " + session + ": exists (sessions are never overwritten)\n");
  // The first session is untouched.
  CHECK(read_file(session) == before);
  const doorbench::SessionReader reader(session);
  CHECK(reader.sample_count("force") == 2000);
  CHECK(reader.metadata().operator_name.empty());
}

TEST_CASE("CLI: record with a broken rig file names its file, line and key", "[cli][session]") {
  ScratchDir scratch;
  const std::string shipped = shipped_rig_text();
  const std::string session = (scratch / "s.h5").string();
  auto record_with = [&](const std::string& text) {
    const std::string rig = scratch.write("broken rig.toml", text).string();
    const RunResult result =
        run_doorbench({"record", "--rig", rig, "--duration-s", "2", "--out", session}, scratch);
    require_failure(result);
    CHECK(!fs::exists(session));
    return std::make_pair(rig, result);
  };

  SECTION("clock.sample_rate_hz misspelt") {
    const std::string text =
        replace_once(shipped, "\nsample_rate_hz = 1000.0", "\nsample_rte_hz = 1000.0");
    const auto [rig, result] = record_with(text);
    CHECK(line_of(text, "sample_rte_hz") == line_of(shipped, "\nsample_rate_hz = 1000.0") + 1);
    CHECK_THAT(result.err, StartsWith("doorbench: " + rig + ":" +
                                      std::to_string(line_of(text, "sample_rte_hz")) +
                                      ": clock.sample_rte_hz: "));
    CHECK_THAT(result.err, Contains("unknown key"));
    CHECK_THAT(result.err, Contains("sample_rate_hz"));  // among the valid keys
  }
  SECTION("the load cell's noise_rms_N negative") {
    const std::string text = replace_once(shipped, "noise_rms_N = 0.2 ", "noise_rms_N = -1  ");
    const auto [rig, result] = record_with(text);
    CHECK_THAT(result.err, StartsWith("doorbench: " + rig + ":" +
                                      std::to_string(line_of(text, "noise_rms_N = -1")) +
                                      ": channels[0].parameters.noise_rms_N: "));
    CHECK_THAT(result.err, Contains("-1"));
    CHECK_THAT(result.err, Contains(">= 0"));
  }
  SECTION("the hand's cycles zero") {
    const std::string text = replace_once(shipped, "cycles = 3 ", "cycles = 0 ");
    const auto [rig, result] = record_with(text);
    CHECK_THAT(result.err,
               StartsWith("doorbench: " + rig + ":" + std::to_string(line_of(text, "cycles = 0")) +
                          ": simulation.hand.cycles: "));
  }
  SECTION("a rig file that is not there") {
    const std::string missing = (scratch / "no-such-rig.toml").string();
    const RunResult result =
        run_doorbench({"record", "--rig", missing, "--duration-s", "2", "--out", session}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + missing + ": "));
    CHECK(!fs::exists(session));
  }
}

TEST_CASE("CLI: record on a comedi rig refuses addresses that are not comedi's", "[cli][session]") {
  ScratchDir scratch;
  std::string text =
      replace_all(shipped_rig_text(), "backend = \"simulated\"", "backend = \"comedi\"");
  const auto simulation = text.find("\n[simulation]");
  REQUIRE(simulation != std::string::npos);
  text.erase(simulation + 1);  // no [simulation] without simulated channels
  const std::string rig = scratch.write("comedi.toml", text).string();
  const std::string session = (scratch / "s.h5").string();
  const RunResult result =
      run_doorbench({"record", "--rig", rig, "--duration-s", "2", "--out", session}, scratch);
  require_failure(result);
  CHECK_THAT(result.err, Contains(rig));
  CHECK_THAT(result.err, Contains("channel force: address \"sim0/ai0\" is not a comedi address "
                                  "SUBDEVICE/CHANNEL, e.g. \"0/3\""));
  CHECK(!fs::exists(session));
}

TEST_CASE("CLI: record --duration-s 0 is a usage error", "[cli][session]") {
  ScratchDir scratch;
  const std::string session = (scratch / "s.h5").string();
  const RunResult result =
      run_doorbench({"record", "--duration-s", "0", "--out", session}, scratch);
  require_usage_error(result);
  CHECK_THAT(result.err, Contains("--duration-s"));
  CHECK(!fs::exists(session));
}

TEST_CASE("CLI: info lists the channels, events and calibration records", "[cli][session]") {
  ScratchDir scratch;
  const std::string session = record_quick_session(scratch);
  const RunResult result = run_doorbench({"info", session}, scratch);
  require_success(result);
  CHECK(result.err.empty());
  INFO("stdout: " << result.out);
  const doorbench::SessionReader reader(session);

  // name, sensor, samples, rate Hz, raw unit, unit, calibration
  const std::vector<std::string> channel_lines = section_lines(result.out, "channels:");
  const std::array<std::array<std::string, 3>, 3> expected = {{{"force", "load_cell", "N"},
                                                               {"angle", "inclinometer", "rad"},
                                                               {"rate", "gyroscope", "rad/s"}}};
  for (const auto& [name, kind, unit] : expected) {
    INFO("channel " << name);
    const auto line = std::find_if(channel_lines.begin(), channel_lines.end(),
                                   [&](const std::string& l) { return words_of(l).at(0) == name; });
    REQUIRE(line != channel_lines.end());
    const std::vector<std::string> words = words_of(*line);
    REQUIRE(words.size() == 7);
    CHECK(words[1] == kind);
    CHECK(words[2] == "3000");
    CHECK(words[3] == "1000");
    CHECK(words[5] == unit);
    CHECK(words[6] == reader.channel(name).calibration_id);
  }

  // events: TOTAL (KIND COUNT, ...)
  const std::vector<doorbench::SessionEvent> events = reader.events();
  auto count = [&](const std::string& kind) {
    return static_cast<double>(
        std::count_if(events.begin(), events.end(), [&](const auto& e) { return e.kind == kind; }));
  };
  REQUIRE(count("stroke_start") >= 4);
  const std::vector<std::string> lines = lines_of(result.out);
  const auto events_line = std::find_if(
      lines.begin(), lines.end(), [](const std::string& l) { return l.rfind("events: ", 0) == 0; });
  REQUIRE(events_line != lines.end());
  CHECK(numbers_after(*events_line, "events:") ==
        std::vector<double>{static_cast<double>(events.size())});
  CHECK(numbers_after(*events_line, "trigger") == std::vector<double>{1.0});
  CHECK(numbers_after(*events_line, "stroke_start") == std::vector<double>{count("stroke_start")});
  CHECK(numbers_after(*events_line, "stroke_end") == std::vector<double>{count("stroke_end")});

  // The three calibration records with their sensors and units.
  const std::vector<std::string> calibration_lines = section_lines(result.out, "calibrations:");
  CHECK(calibration_lines.size() == 3);
  const auto records = reader.calibrations();
  REQUIRE(records.size() == 3);
  for (const auto& record : records) {
    INFO("record " << record.id);
    const auto line =
        std::find_if(calibration_lines.begin(), calibration_lines.end(),
                     [&](const std::string& l) { return words_of(l).at(0) == record.id; });
    REQUIRE(line != calibration_lines.end());
    CHECK_THAT(*line, Contains(record.sensor_kind));
    CHECK_THAT(*line, Contains(record.sensor_serial));
    CHECK_THAT(*line, Contains(" " + record.unit + " = "));
  }
}

TEST_CASE("CLI: info and export fail with exit 1 on a missing file or one that is not a session",
          "[cli][session]") {
  ScratchDir scratch;
  const std::string csv = (scratch / "out.csv").string();
  SECTION("info of a missing file") {
    const std::string missing = (scratch / "no-such-session.h5").string();
    const RunResult result = run_doorbench({"info", missing}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + missing + ": "));
  }
  SECTION("info of a text file") {
    const std::string text = scratch.write("text.h5", "time_s,force_N\n0,0\n").string();
    const RunResult result = run_doorbench({"info", text}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + text + ": "));
    CHECK_THAT(result.err, Contains("not a doorbench session"));
  }
  SECTION("export of a missing file") {
    const std::string missing = (scratch / "no-such-session.h5").string();
    const RunResult result = run_doorbench({"export", missing, "--csv", csv}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, StartsWith("doorbench: " + missing + ": "));
    CHECK(!fs::exists(csv));
  }
  SECTION("export of a text file") {
    const std::string text = scratch.write("text.h5", "time_s,force_N\n0,0\n").string();
    const RunResult result = run_doorbench({"export", text, "--csv", csv}, scratch);
    require_failure(result);
    CHECK_THAT(result.err, Contains("not a doorbench session"));
    CHECK(!fs::exists(csv));
  }
}

TEST_CASE("CLI: export writes the session's physical values, strokes and the signed force",
          "[cli][session]") {
  ScratchDir scratch;
  const std::string session = record_quick_session(scratch);
  const std::string csv = (scratch / "quick.csv").string();
  const RunResult result = run_doorbench({"export", session, "--csv", csv}, scratch);
  require_success(result);
  CHECK(result.out.empty());
  CHECK_THAT(result.err, !StartsWith("doorbench: "));

  const doorbench::CsvTable table = doorbench::parse_csv_table(read_file(csv), csv);
  CHECK(table.column_names == std::vector<std::string>{"time_s", "force_N", "rate_rad_s", "stroke",
                                                       "inclinometer_angle_rad"});
  const doorbench::Recording run = doorbench::read_recording_csv(csv);
  REQUIRE(run.handle_radius_m);
  CHECK(*run.handle_radius_m == 0.58);
  REQUIRE(run.sample_rate_hz);
  CHECK(*run.sample_rate_hz == 1000.0);
  REQUIRE(run.size() == 3000);
  REQUIRE(run.rate_rad_s);
  REQUIRE(run.stroke);
  CHECK(!run.angle_rad);  // the inclinometer is narrow-range, not the door angle
  REQUIRE(run.extra_names == std::vector<std::string>{"inclinometer_angle_rad"});

  // The values are the session's physical values.
  const doorbench::SessionReader reader(session);
  const doorbench::ChannelSlice force_slice = reader.read("force");
  const std::vector<double> force = reader.physical("force", force_slice);
  CHECK(run.time_s == force_slice.time_s);
  CHECK(*run.rate_rad_s == reader.physical("rate", reader.read("rate")));
  CHECK(run.extra_columns[0] == reader.physical("angle", reader.read("angle")));

  // Strokes are numbered 1, 2, ... in order, each one run of rows; 0 between them.
  const std::vector<int>& stroke = *run.stroke;
  int strokes = 0;
  for (std::size_t i = 1; i < stroke.size(); ++i) {
    if (stroke[i] != stroke[i - 1] && stroke[i] != 0) {
      if (stroke[i] != strokes + 1)
        FAIL("row " << i << ": stroke " << stroke[i] << " after " << strokes);
      strokes = stroke[i];
    }
  }
  CHECK(stroke.front() == 0);
  // As many as the session's stroke_start events; the odd ones are the openings.
  std::vector<std::string> details;
  for (const auto& event : reader.events()) {
    if (event.kind == "stroke_start") details.push_back(event.detail);
  }
  REQUIRE(strokes == static_cast<int>(details.size()));
  REQUIRE(strokes >= 4);
  for (int k = 1; k <= strokes; ++k) {
    CHECK(details[static_cast<std::size_t>(k - 1)] == (k % 2 == 1 ? "opening" : "closing"));
  }

  // The force is the load cell's reading, + in openings and − in closings: mostly positive
  // in the openings, mostly negative in the closings, and following the hand's true force.
  const std::vector<double> truth = reader.read_group_dataset("truth", "force_N");
  REQUIRE(truth.size() == run.size());
  std::map<int, std::array<int, 2>> signs;  // stroke: {positive, negative} rows
  std::size_t pressed = 0, following = 0;
  for (std::size_t i = 0; i < run.size(); ++i) {
    if (std::abs(run.force_N[i]) != std::abs(force[i])) {
      FAIL("row " << i << ": force_N " << run.force_N[i] << " is not ± " << force[i]);
    }
    if (stroke[i] == 0) continue;
    const double mounting = stroke[i] % 2 == 1 ? 1.0 : -1.0;
    if (run.force_N[i] != mounting * force[i]) {
      FAIL("row " << i << " (stroke " << stroke[i] << "): force_N " << run.force_N[i] << " is not "
                  << mounting << " × " << force[i]);
    }
    if (run.force_N[i] > 0) ++signs[stroke[i]][0];
    if (run.force_N[i] < 0) ++signs[stroke[i]][1];
    if (mounting * truth[i] > 5.0) {  // the hand presses the load cell
      ++pressed;
      if (std::abs(run.force_N[i] - truth[i]) < 0.05 * std::abs(truth[i]) + 2.0) ++following;
    }
  }
  for (const auto& [id, count] : signs) {
    INFO("stroke " << id << ": " << count[0] << " rows positive, " << count[1] << " negative");
    const int mostly = id % 2 == 1 ? count[0] : count[1];
    CHECK(mostly > 2 * (count[0] + count[1]) / 3);
  }
  INFO(following << " of " << pressed << " pressed rows follow the true force");
  CHECK(pressed > 500);
  CHECK(following > 0.95 * static_cast<double>(pressed));
}

TEST_CASE("CLI: import of an exported CSV and export again give back the same columns",
          "[cli][session]") {
  ScratchDir scratch;
  const std::string session = record_quick_session(scratch);
  const std::string first_csv = (scratch / "first.csv").string();
  require_success(run_doorbench({"export", session, "--csv", first_csv}, scratch));

  const std::string imported = (scratch / "imported.h5").string();
  const RunResult result = run_doorbench(
      {"import", first_csv, "--out", imported, "--operator", "Ann", "--product", "DW-60"}, scratch);
  require_success(result);
  CHECK(result.out.empty());
  CHECK_THAT(result.err, !StartsWith("doorbench: "));
  CHECK_THAT(result.err, Contains(imported));

  const std::string second_csv = (scratch / "second.csv").string();
  require_success(run_doorbench({"export", imported, "--csv", second_csv}, scratch));

  const doorbench::Recording first = doorbench::read_recording_csv(first_csv);
  const doorbench::Recording second = doorbench::read_recording_csv(second_csv);
  REQUIRE(second.size() == first.size());
  CHECK(second.force_N == first.force_N);
  REQUIRE(second.rate_rad_s);
  CHECK(*second.rate_rad_s == *first.rate_rad_s);
  REQUIRE(second.stroke);
  CHECK(*second.stroke == *first.stroke);
  CHECK(second.time_s == first.time_s);
  CHECK(second.extra_names == first.extra_names);
  CHECK(second.extra_columns == first.extra_columns);
  CHECK(!second.angle_rad);
  REQUIRE(second.handle_radius_m);
  CHECK(*second.handle_radius_m == 0.58);

  const doorbench::SessionReader reader(imported);
  CHECK(reader.metadata().operator_name == "Ann");
  CHECK(reader.metadata().product_id == "DW-60");
  CHECK(reader.sample_count("force") == first.size());
  CHECK(reader.channel("force").unit == "N");
  CHECK(reader.channel("rate").unit == "rad/s");
}

TEST_CASE("CLI: import rejects a broken CSV, naming its line, and leaves no session",
          "[cli][session]") {
  ScratchDir scratch;
  const std::string session = (scratch / "s.h5").string();
  std::vector<std::string> rows = csv_rows(20);  // row 4 is on line 7
  SECTION("a row with a missing field") {
    rows[4] = rows[4].substr(0, rows[4].rfind(','));
  }
  SECTION("time_s not increasing") {
    rows[4] = doorbench::format_csv_number(3 / 1000.0) + rows[4].substr(rows[4].find(','));
  }
  const std::string csv = scratch.write("broken.csv", csv_text(rows)).string();
  REQUIRE(lines_of(read_file(csv)).at(6) == rows[4]);
  const RunResult result = run_doorbench({"import", csv, "--out", session}, scratch);
  require_failure(result);
  CHECK_THAT(result.err, StartsWith("doorbench: " + csv + ":7: "));
  CHECK(!fs::exists(session));
}

TEST_CASE("CLI: import refuses to overwrite a session", "[cli][session]") {
  ScratchDir scratch;
  const std::string csv = scratch.write("run.csv", csv_text(csv_rows(20))).string();
  const std::string session = scratch.write("s.h5", "not yet a session").string();
  const RunResult result = run_doorbench({"import", csv, "--out", session}, scratch);
  CHECK(result.exit_code == 2);  // refused before anything is read (docs/output-files.md)
  CHECK(result.err == "doorbench: " + session + ": exists (sessions are never overwritten)\n");
  CHECK(read_file(session) == "not yet a session");
}

// Known bug: import makes a uniform clock of rate 1 / mean interval, which for 30 rows at
// 100 Hz (t = 0, 0.01, ..., 0.29) is 100.00000000000001 Hz; the clock's times then fall an
// ulp below the CSV's, while the stroke events keep the CSV's times, so export starts and
// ends every stroke one row late (and time_s comes back as 0.009999999999999998, ...).
TEST_CASE("CLI: import and export keep the times and strokes of a 100 Hz recording",
          "[cli][session]") {
  ScratchDir scratch;
  std::string text = "# handle_radius_m: 0.58\ntime_s,force_N,rate_rad_s,stroke\n";
  for (int row = 0; row < 30; ++row) {
    const int stroke = row >= 5 && row < 10 ? 1 : row >= 15 && row < 20 ? 2 : 0;
    text += doorbench::format_csv_number(row / 100.0) + "," + std::to_string(row) + "," +
            doorbench::format_csv_number(row / 10.0) + "," + std::to_string(stroke) + "\n";
  }
  const std::string csv = scratch.write("100hz.csv", text).string();
  const std::string session = (scratch / "100hz.h5").string();
  const std::string again = (scratch / "again.csv").string();
  require_success(run_doorbench({"import", csv, "--out", session}, scratch));
  require_success(run_doorbench({"export", session, "--csv", again}, scratch));
  const doorbench::Recording original = doorbench::read_recording_csv(csv);
  const doorbench::Recording exported = doorbench::read_recording_csv(again);
  REQUIRE(exported.size() == original.size());
  CHECK(exported.force_N == original.force_N);
  REQUIRE(exported.stroke);
  CHECK(*exported.stroke == *original.stroke);
  CHECK(exported.time_s == original.time_s);
}

TEST_CASE("CLI: fit and loop refuse bad usage and missing data", "[cli][fit]") {
  ScratchDir scratch;
  const std::string out = (scratch / "out").string();
  // The loop compares held-out errors: two folds would fit each direction on the other.
  require_usage_error(run_doorbench({"loop", "data.csv", "--folds", "2", "--out", out}, scratch));
  require_usage_error(
      run_doorbench({"fit", "data.csv", "--objective", "best", "--out", out}, scratch));
  require_usage_error(run_doorbench({"fit", "data.csv"}, scratch));
  const RunResult missing =
      run_doorbench({"fit", (scratch / "nowhere.csv").string(), "--out", out}, scratch);
  // Progress lines come first; the error is the last line.
  CHECK(missing.exit_code == 1);
  CHECK_THAT(missing.err, EndsWith("nowhere.csv: cannot open for reading\n"));
  const RunResult unknown_effect = run_doorbench(
      {"fit", (scratch / "nowhere.csv").string(), "--effects", "stribeck,wobble", "--out", out},
      scratch);
  CHECK(unknown_effect.exit_code != 0);
}

TEST_CASE("CLI: fit writes result.json, the report and plots for a simulated run", "[cli][fit]") {
  ScratchDir scratch;
  // Two opening-closing runs of the reference sensory door by the virtual hand, exact.
  const std::string run = (scratch / "run.csv").string();
  require_success(run_doorbench(
      {"simulate", "--model", "sensory", "--hand", "open-close", "--duration-s", "5", "--out", run},
      scratch));
  const std::string out = (scratch / "fit").string();
  const RunResult result =
      run_doorbench({"fit", run, "--model", "sensory", "--folds", "0", "--out", out}, scratch);
  require_success(result);
  CHECK_THAT(result.out, Contains("Fit of the sensory model"));
  for (const char* file : {"result.json", "report.md", "fitted-params.json", "rate.svg",
                           "force-angle.svg", "residual-angle.svg", "residual-speed.svg"}) {
    INFO(file);
    CHECK(std::filesystem::exists(std::filesystem::path(out) / file));
  }
  // The fitted file is a parameter file doorbench reads back.
  const std::string grid = (scratch / "grid.csv").string();
  std::ofstream(grid) << "theta_rad,omega_rad_s\n0.02,0\n";
  require_success(run_doorbench(
      {"model", "torque", "--model", "sensory", "--params", out + "/fitted-params.json", "--in",
       grid, "--out", (scratch / "torque.csv").string()},
      scratch));
}
