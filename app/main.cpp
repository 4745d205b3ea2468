// doorbench: record, model, fit and play back the feel of a product mechanism.
// Exit status: 0 success, 1 failure, 2 bad usage. Errors go to stderr on one line.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "acquisition/output_file.h"
#include "acquisition/printable.h"
#include "app/commands.h"

namespace {

// CLI11 reports a mistyped verb only as "a subcommand is required"; name the word instead.
std::string unknown_verb_message(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') return "";
    const auto subcommands = level->get_subcommands([](const CLI::App*) { return true; });
    const CLI::App* next = nullptr;
    std::string expected;
    for (const CLI::App* sub : subcommands) {
      if (sub->get_name() == word) next = sub;
      expected += (expected.empty() ? "" : ", ") + sub->get_name();
    }
    if (next == nullptr) {
      if (subcommands.empty()) return "";
      return "unknown verb '" + path + word + "' (expected " + expected + ")";
    }
    path += word + " ";
    level = next;
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "doorbench: measure a door's feel on the bench, fit models to it and play it back.\n"
      "Run `doorbench VERB --help` for each verb."};
  app.set_version_flag("--version", std::string("doorbench ") + DOORBENCH_VERSION);
  app.require_subcommand(1);
  doorbench::app::Action action;
  doorbench::app::add_model_command(app, action);
  doorbench::app::add_simulate_command(app, action);
  doorbench::app::add_session_commands(app, action);
  doorbench::app::add_fit_command(app, action);
  doorbench::app::add_loop_command(app, action);
  doorbench::app::add_demo_command(app, action);
  doorbench::app::add_calibrate_command(app, action);
  doorbench::app::add_calibration_command(app, action);
  doorbench::app::add_devices_command(app, action);
  doorbench::app::add_view_command(app, action);
  doorbench::app::add_play_command(app, action);
  doorbench::app::add_ab_command(app, action);
  doorbench::app::add_spec_command(app, action);
  doorbench::app::add_hapticmaster_command(app, action);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForVersion& version) {
    return app.exit(version);
  } catch (const CLI::ParseError& error) {
    std::string message = unknown_verb_message(app, argc, argv);
    if (message.empty()) message = error.what();
    std::cerr << "doorbench: " << message << " (see doorbench --help)\n";
    return 2;
  }

  try {
    if (action) action();
    return 0;
  } catch (const doorbench::app::UsageError& error) {
    std::cerr << "doorbench: " << doorbench::printable(error.what()) << " (see doorbench --help)\n";
    return 2;
  } catch (const doorbench::OutputRefused& error) {  // an existing output, or an input
    std::cerr << "doorbench: " << doorbench::printable(error.what()) << "\n";
    return 2;
  } catch (const std::exception& error) {
    // Messages quote files' text: control characters are shown escaped.
    std::cerr << "doorbench: " << doorbench::printable(error.what()) << "\n";
    return 1;
  }
}
