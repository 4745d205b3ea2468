// Every verb of the doorbench command, registered in the order `doorbench --help` lists
// them, then each numeric option's check (app/number_options.h).
#include "app/commands.h"
#include "app/number_options.h"

namespace doorbench::app {

void add_all_verbs(CLI::App& app, Action& action) {
  add_model_command(app, action);
  add_simulate_command(app, action);
  add_record_command(app, action);
  add_recover_command(app, action);
  add_info_command(app, action);
  add_export_command(app, action);
  add_import_command(app, action);
  add_fit_command(app, action);
  add_loop_command(app, action);
  add_demo_command(app, action);
  add_calibrate_command(app, action);
  add_calibration_command(app, action);
  add_devices_command(app, action);
  add_view_command(app, action);
  add_play_command(app, action);
  add_ab_command(app, action);
  add_spec_command(app, action);
  add_hapticmaster_command(app, action);
  CLI::App* campaign = add_campaign_command(app, action);
  add_campaign_analyze(*campaign, action);
  add_campaign_report(*campaign, action);
  // After every verb, so that each numeric option is covered by itself.
  check_numeric_options(app);
}

}  // namespace doorbench::app
