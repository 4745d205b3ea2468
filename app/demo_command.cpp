// doorbench demo: the main job on the simulated bench. For now: the reference door opened
// and closed by the virtual hand with both models, a summary each, the runs on disk.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "acquisition/recording_csv.h"
#include "analysis/parameter_file.h"
#include "analysis/run_summary.h"
#include "analysis/trajectory_io.h"
#include "app/commands.h"
#include "app/hand_run.h"

namespace doorbench::app {
namespace {

struct DemoOptions {
  std::string out_dir = "doorbench-demo";
};

void run_demo(const DemoOptions& options) {
  const std::filesystem::path dir = options.out_dir;
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw std::runtime_error(dir.string() + ": cannot create folder: " + error.message());
  std::cout << "doorbench demo: the reference door on the simulated bench, opened to 80 deg and "
               "closed again by the virtual hand (10 s at 1 kHz)\n";
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel model = reference_model(kind);
    const Trajectory run = simulate_hand(model, VirtualHandOptions{}, 1000.0);
    const std::filesystem::path run_path = dir / (std::string(to_string(kind)) + "-open-close.csv");
    write_recording_csv_file(
        run_path, to_recording(run, "doorbench demo, reference door, " +
                                        std::string(to_string(kind)) + " model, virtual hand"));
    const std::filesystem::path params_path = dir / (std::string(to_string(kind)) + "-params.json");
    std::ofstream(params_path) << to_parameter_json(model);
    std::cout << "\n"
              << to_string(kind) << " model (" << run_path.string() << "):\n"
              << format_summary(summarize_run(model, run));
  }
  std::cout << "\nruns and parameter files are in " << dir.string() << "/\n";
}

}  // namespace

void add_demo_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* demo = app.add_subcommand(
      "demo", "Run the main job on the simulated bench (no hardware needed) and summarize it");
  demo->add_option("--out", options->out_dir, "Folder for the runs")->capture_default_str();
  demo->callback([options, &action] { action = [options] { run_demo(*options); }; });
}

}  // namespace doorbench::app
