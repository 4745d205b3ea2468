// doorbench devices: the comedi DAQ devices this machine has, with their subdevices,
// channels, maxdata and ranges. Run with $DOORBENCH_COMEDI_LIBRARY naming the device
// emulator (tests/comedi_emulator) and --dev-dir its device files, it lists those.
#include <iostream>
#include <memory>

#include "app/commands.h"
#include "sensors/comedi_api.h"
#include "sensors/comedi_devices.h"

namespace doorbench::app {

namespace {

struct DevicesOptions {
  std::string dev_dir = "/dev";
};

void run_devices(const DevicesOptions& options) {
  const sensors::ComediApi& api = sensors::selected_comedi_api();
  std::cout << "comedi devices in " << options.dev_dir << " (through " << api.name << "):\n"
            << sensors::comedi_devices_report(api, options.dev_dir)
            << "Modbus sensors: not probed (doorbench has no Modbus backend yet)\n";
}

}  // namespace

void add_devices_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<DevicesOptions>();
  CLI::App* command = app.add_subcommand(
      "devices",
      "List the comedi DAQ devices (/dev/comedi*) with their subdevices, channels, maxdata and "
      "ranges");
  command->add_option("--dev-dir", options->dev_dir,
                      "Where to look for comedi0, comedi1, ... (default /dev)");
  command->callback([options, &action] { action = [options] { run_devices(*options); }; });
}

}  // namespace doorbench::app
