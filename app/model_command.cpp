// doorbench model torque: τ_m and each term over a grid of (θ, ω).
#include <fstream>
#include <memory>

#include "acquisition/session/csv_table.h"
#include "acquisition/session/output_file.h"
#include "analysis/model/parameter_file.h"
#include "app/commands.h"

namespace doorbench::app {

void add_model_options(CLI::App& command, ModelOptions& options) {
  command.add_option("--model", options.model, "Which door model")
      ->check(CLI::IsMember({"sensory", "physical"}))
      ->capture_default_str();
  command.add_option("--params", options.params_path,
                     "Parameter file (JSON, the layout of reference-door.json); default: the "
                     "reference door built into doorbench");
  command.add_option("--effects", options.effects_path,
                     "Effects file (JSON) naming extra effects to switch on and their values");
}

DoorModel load_model(const ModelOptions& options) {
  const std::optional<ModelKind> kind = parse_model_kind(options.model);
  if (!kind) throw UsageError("--model must be sensory or physical, not " + options.model);
  return doorbench::load_model(*kind, options.params_path, options.effects_path);
}

namespace {

struct TorqueOptions {
  ModelOptions model;
  std::string grid_path;
  std::string out_path;
  bool overwrite = false;
};

void run_torque(const TorqueOptions& options) {
  std::vector<std::filesystem::path> inputs{options.grid_path};
  for (const std::string* input : {&options.model.params_path, &options.model.effects_path}) {
    if (!input->empty()) inputs.emplace_back(*input);
  }
  check_output_file(options.out_path, inputs, options.overwrite);
  const DoorModel model = load_model(options.model);
  const CsvTable grid = read_csv_file(options.grid_path);
  const auto theta_column = grid.find_column("theta_rad");
  const auto omega_column = grid.find_column("omega_rad_s");
  for (const auto& [column, name] :
       {std::pair{theta_column, "theta_rad"}, std::pair{omega_column, "omega_rad_s"}}) {
    if (!column) {
      throw CsvError(options.grid_path, grid.header_line,
                     std::string("header lacks required column ") + name);
    }
  }
  const std::vector<double>& theta = grid.columns[*theta_column];
  const std::vector<double>& omega = grid.columns[*omega_column];
  const std::size_t rows = grid.row_count();
  std::vector<double> total(rows);
  std::vector<std::vector<double>> terms(model.term_count(), std::vector<double>(rows));
  std::array<double, DoorModel::kMaxTerms> row_terms;
  for (std::size_t i = 0; i < rows; ++i) {
    total[i] = model.torque_Nm(theta[i], omega[i], row_terms);
    for (int term = 0; term < model.term_count(); ++term) terms[term][i] = row_terms[term];
  }
  std::vector<std::string> names = {"theta_rad", "omega_rad_s", "tau_Nm"};
  std::vector<const std::vector<double>*> columns = {&theta, &omega, &total};
  for (int term = 0; term < model.term_count(); ++term) {
    names.push_back("tau_" + model.term_name(term) + "_Nm");
    columns.push_back(&terms[term]);
  }
  const CsvMetadata metadata = {
      {"source", "doorbench model torque --model " + options.model.model},
      {"params", options.model.params_path.empty() ? "reference door" : options.model.params_path},
      {"handle_radius_m", format_csv_number(model.geometry().handle_radius_m)}};
  write_file_atomically(options.out_path,
                        [&](std::ostream& out) { write_csv(out, metadata, names, columns); });
}

}  // namespace

void add_model_command(CLI::App& app, Action& action) {
  CLI::App* model = app.add_subcommand("model", "Evaluate the door models");
  model->require_subcommand(1);
  auto options = std::make_shared<TorqueOptions>();
  CLI::App* torque = model->add_subcommand(
      "torque",
      "Mechanism torque tau_m(theta, omega) and every term's contribution over a grid.\n"
      "GRID.csv has columns theta_rad,omega_rad_s; OUT.csv repeats them and adds tau_Nm and "
      "one tau_<term>_Nm column per term (N*m, positive = opening).");
  add_model_options(*torque, options->model);
  torque->add_option("--in", options->grid_path, "Grid of (theta, omega) points (CSV)")->required();
  torque->add_option("--out", options->out_path, "Where to write the torques (CSV)")->required();
  torque->add_flag("--overwrite", options->overwrite, "Replace an existing --out file");
  torque->callback([options, &action] { action = [options] { run_torque(*options); }; });
}

}  // namespace doorbench::app
