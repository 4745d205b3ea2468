#pragma once
// Each verb of the doorbench command registers its options and, when chosen, the action
// that main() runs after parsing. Actions throw UsageError for wrong combinations of
// options (exit 2), OutputRefused (acquisition/session/output_file.h) for an output that exists
// or is an input (exit 2), and any other std::exception for failures (exit 1); main()
// prints the message after "doorbench: ", control characters escaped.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>

#include "analysis/model/door_model.h"

namespace doorbench::app {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Action = std::function<void()>;

void add_model_command(CLI::App& app, Action& action);
void add_simulate_command(CLI::App& app, Action& action);
void add_demo_command(CLI::App& app, Action& action);
void add_record_command(CLI::App& app, Action& action);
void add_recover_command(CLI::App& app, Action& action);
void add_info_command(CLI::App& app, Action& action);
void add_export_command(CLI::App& app, Action& action);
void add_import_command(CLI::App& app, Action& action);
void add_fit_command(CLI::App& app, Action& action);
void add_loop_command(CLI::App& app, Action& action);
void add_calibrate_command(CLI::App& app, Action& action);
void add_calibration_command(CLI::App& app, Action& action);
void add_devices_command(CLI::App& app, Action& action);
void add_view_command(CLI::App& app, Action& action);
void add_play_command(CLI::App& app, Action& action);
void add_ab_command(CLI::App& app, Action& action);
void add_spec_command(CLI::App& app, Action& action);
void add_hapticmaster_command(CLI::App& app, Action& action);
// `campaign` and its plan, run and merge; returns the campaign subcommand, to which other
// campaign subcommands (e.g. `campaign analyze`) attach in main.cpp.
CLI::App* add_campaign_command(CLI::App& app, Action& action);
// The demo's short simulated campaign into `dir`, a summary line per block on `out`. An
// earlier demo's campaign in dir/folder is replaced; any other non-empty dir/folder is refused
// (OutputRefused).
void run_demo_campaign(const std::filesystem::path& dir, std::ostream& out);
// `campaign analyze`, added to the `campaign` verb (app/campaign_analyze_command.cpp).
void add_campaign_analyze(CLI::App& campaign, Action& action);
// `campaign report`, the report again from an analysis (app/campaign_report_command.cpp).
void add_campaign_report(CLI::App& campaign, Action& action);
// Every verb above, then the check of every numeric option (app/number_options.h): what
// main() registers, and what tests parse command lines with (app/verbs.cpp).
void add_all_verbs(CLI::App& app, Action& action);

// The options every verb that builds a model shares.
struct ModelOptions {
  std::string model = "sensory";
  std::string params_path;   // empty: the reference door
  std::string effects_path;  // empty: no effects
};
void add_model_options(CLI::App& command, ModelOptions& options);
DoorModel load_model(const ModelOptions& options);

}  // namespace doorbench::app
