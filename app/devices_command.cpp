// doorbench devices: the comedi DAQ devices this machine has, with their subdevices,
// channels, maxdata and ranges. Run with $DOORBENCH_COMEDI_LIBRARY naming the device
// emulator (tests/comedi_emulator) and --dev-dir its device files, it lists those. With
// --rig it also probes the rig's Modbus devices: each channel read once (docs/modbus.md).
#include <iostream>
#include <memory>

#include "acquisition/rig/rig_file.h"
#include "app/commands.h"
#include "sensors/comedi_api.h"
#include "sensors/comedi_devices.h"
#include "sensors/modbus_source.h"

namespace doorbench::app {

namespace {

struct DevicesOptions {
  std::string dev_dir = "/dev";
  std::string rig_path;  // empty: no Modbus probing
};

void run_devices(const DevicesOptions& options) {
  const sensors::ComediApi& api = sensors::selected_comedi_api();
  std::cout << "comedi devices in " << options.dev_dir << " (through " << api.name << "):\n"
            << sensors::comedi_devices_report(api, options.dev_dir);
  if (options.rig_path.empty()) {
    std::cout << "Modbus sensors: not probed (give --rig FILE to probe the rig's)\n";
    return;
  }
  const RigDefinition rig = read_rig_file(options.rig_path);
  std::cout << "Modbus sensors of " << options.rig_path << ":\n"
            << sensors::modbus_probe_report(rig);
}

}  // namespace

void add_devices_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<DevicesOptions>();
  CLI::App* command = app.add_subcommand(
      "devices",
      "List the comedi DAQ devices (/dev/comedi*) with their subdevices, channels, maxdata and "
      "ranges; with --rig, read each of the rig's Modbus sensors once");
  command->add_option("--dev-dir", options->dev_dir,
                      "Where to look for comedi0, comedi1, ... (default /dev)");
  command->add_option("--rig", options->rig_path,
                      "A rig file whose Modbus devices to probe: each channel is read once and "
                      "its value, unit and latency (or the error) printed");
  command->callback([options, &action] { action = [options] { run_devices(*options); }; });
}

}  // namespace doorbench::app
