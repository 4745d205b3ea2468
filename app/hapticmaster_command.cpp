// doorbench hapticmaster check hapticmaster://HOST[:PORT]: the bring-up check of a real
// HapticMaster (haptic/hapticmaster_check.h, docs/hapticmaster.md): start-up checks, the
// round-trip time distribution, the stiffness limit it implies, and (confirmed) what a
// disconnect leaves on the device. Prints the report, writes it as JSON with --json; exits 1
// when a check failed.
#include <unistd.h>

#include <iostream>
#include <memory>

#include "acquisition/session/output_file.h"
#include "app/commands.h"
#include "app/number_options.h"
#include "haptic/hapticmaster_check.h"

namespace doorbench::app {
namespace {

struct CheckOptions {
  std::string uri;
  int exchanges = 3000;
  double inertia_kg = 10.0;
  bool yes = false;
  std::string json_path;
  bool overwrite = false;
};

void run_check(const CheckOptions& options) {
  constexpr std::string_view kScheme = "hapticmaster://";
  if (options.uri.rfind(kScheme, 0) != 0 || options.uri.size() == kScheme.size()) {
    throw UsageError("hapticmaster check: '" + options.uri + "' is not hapticmaster://HOST[:PORT]");
  }
  // The output rule (acquisition/session/output_file.h): refused before the device is touched.
  if (!options.json_path.empty()) check_output_file(options.json_path, {}, options.overwrite);
  haptic::HapticMasterCheckOptions check;
  check.exchanges = options.exchanges;
  check.inertia_kg = options.inertia_kg;
  check.driver.progress = [](const std::string& line) { std::cerr << line << "\n"; };
  const bool yes = options.yes;
  check.confirm = [yes](const std::string& what) {
    std::cerr << what << "\n";
    if (yes) {
      std::cerr << "confirmed by --yes\n";
      return true;
    }
    if (isatty(STDIN_FILENO) == 0) {
      std::cerr << "no terminal to confirm on: skipped (give --yes to run it)\n";
      return false;
    }
    std::cerr << "Run this test? [y/N] " << std::flush;
    std::string answer;
    std::getline(std::cin, answer);
    return answer == "y" || answer == "Y" || answer == "yes";
  };
  const haptic::HapticMasterCheckReport report =
      haptic::run_hapticmaster_check(options.uri.substr(kScheme.size()), check);
  std::cout << report.text();
  if (!options.json_path.empty())
    write_text_file_atomically(options.json_path, report.json() + "\n");
  if (!report.passed()) throw std::runtime_error("hapticmaster check: a check failed");
}

}  // namespace

void add_hapticmaster_command(CLI::App& app, Action& action) {
  CLI::App* group = app.add_subcommand("hapticmaster", "Bring-up of a real HapticMaster");
  group->require_subcommand(1);
  auto options = std::make_shared<CheckOptions>();
  CLI::App* check = group->add_subcommand(
      "check",
      "First contact with a device: start-up checks (emergency signals, calibration and "
      "homing, other programs' effects, workspace, inertia), the round-trip time (p50/p99/max), "
      "the stiffness limit it implies, and (confirmed) whether a disconnect leaves force on");
  check->add_option("device", options->uri, "hapticmaster://HOST[:PORT]")->required();
  check->add_option("--exchanges", options->exchanges, "Round trips to time")
      ->check(number_range(100, 1000000))
      ->capture_default_str();
  check
      ->add_option("--inertia-kg", options->inertia_kg,
                   "The inertia rendered during the check (heavy: the arm barely moves)")
      ->check(number_range(2.0, 100.0))
      ->capture_default_str();
  check->add_flag("--yes", options->yes,
                  "Run the disconnect test without asking (it pushes the arm with 2 N)");
  check->add_option("--json", options->json_path, "Also write the report as JSON");
  check->add_flag("--overwrite", options->overwrite, "Replace an existing --json file");
  check->callback([options, &action] { action = [options] { run_check(*options); }; });
}

}  // namespace doorbench::app
