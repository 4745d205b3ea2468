// doorbench calibration show|apply|certificate: the calibration store and sessions'
// records on the command line (docs/calibration.md).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "acquisition/rig/calibration_store.h"
#include "acquisition/session/output_file.h"
#include "acquisition/session/session_file.h"
#include "app/commands.h"
#include "calibration/certificate.h"
#include "calibration/procedure.h"
#include "calibration/range_warnings.h"

namespace doorbench::app {
namespace {

namespace cal = calibration;

struct CalibrationCommandOptions {
  std::string store_dir;
  std::string what;  // show: an id or a session; apply: the session
  std::string record_id;
  std::string channel;
  std::string out;
  bool overwrite = false;  // certificate: replace an existing --out file
};

CalibrationStore store_of(const CalibrationCommandOptions& o) {
  return CalibrationStore(
      calibration_store_directory(o.store_dir, std::filesystem::current_path()));
}

std::string formula(const CalibrationRecord& r) {
  std::string text = r.unit + " = ";
  for (std::size_t k = 0; k < r.coefficients.size(); ++k) {
    text += (k ? " + " : "") + cal::shortest(r.coefficients[k]) +
            (k == 0   ? ""
             : k == 1 ? "·x"
                      : "·x^" + std::to_string(k));
  }
  return text;
}

void show_record(const CalibrationRecord& r) {
  std::cout << r.id << " (version " << r.version
            << (r.supersedes.empty() ? "" : ", supersedes " + r.supersedes) << ")\n"
            << "  sensor      " << r.sensor_kind << " " << r.sensor_serial << "\n"
            << "  date        " << r.date_utc
            << (r.operator_name.empty() ? "" : " by " + r.operator_name) << "\n  valid until "
            << (r.valid_until_utc.empty() ? "no expiry" : r.valid_until_utc) << "\n  method      "
            << r.method << "\n";
  if (!r.references.empty()) std::cout << "  references  " << r.references << "\n";
  std::cout << "  " << formula(r) << " (x in " << r.input_unit << "), standard uncertainty "
            << cal::shortest(r.standard_uncertainty) << " " << r.unit << "\n";
  if (r.delay_s != 0) {
    std::cout << "  delay       " << cal::fixed(r.delay_s * 1e3, 3) << " ms ± "
              << cal::fixed(r.delay_standard_uncertainty_s * 1e3, 3) << " ms (corrected on read)\n";
  }
  for (const CalibrationQuantity& q : r.quantities) {
    std::printf("  %-28s %14.6g", q.name.c_str(), q.value);
    if (q.standard_uncertainty > 0) std::printf(" ± %-12.3g", q.standard_uncertainty);
    std::printf(" %s\n", q.unit.c_str());
  }
  std::fflush(stdout);
  if (!r.points.empty()) std::cout << "  " << r.points.size() << " reference points\n";
  if (!r.notes.empty()) std::cout << "  notes       " << r.notes << "\n";
}

bool is_session(const std::string& what) {
  std::error_code error;
  return std::filesystem::is_regular_file(what, error) &&
         (what.ends_with(".h5") || what.ends_with(".hdf5"));
}

void run_show(const CalibrationCommandOptions& o) {
  if (o.what.empty()) {
    const CalibrationStore store = store_of(o);
    const auto records = store.records();
    std::cout << "calibration store " << store.directory().string() << ": " << records.size()
              << " records\n";
    for (const CalibrationRecord& r : records) {
      std::printf("  %-40s %-13s %-18s v%-3d %-21s %s\n", r.id.c_str(), r.sensor_kind.c_str(),
                  r.sensor_serial.c_str(), r.version, r.date_utc.c_str(),
                  r.method.substr(0, 60).c_str());
    }
    std::fflush(stdout);
    return;
  }
  if (!is_session(o.what)) {
    show_record(store_of(o).get(o.what));
    return;
  }
  const SessionReader session(o.what);
  std::cout << "session " << o.what << "\n";
  for (const ChannelInfo& c : session.channels()) {
    std::cout << "  channel " << c.name << " (" << c.sensor_kind << " " << c.sensor_serial
              << ") uses " << (c.calibration_id.empty() ? "no record" : c.calibration_id)
              << (c.geometry_calibration_id.empty() ? ""
                                                    : ", geometry " + c.geometry_calibration_id)
              << "\n";
  }
  for (const std::string& warning : cal::range_warnings(session)) {
    std::cout << "  warning: " << warning << "\n";
  }
  for (const SessionEvent& e : session.events()) {
    if (e.kind == "calibration") std::cout << "  event: " << e.channel << ": " << e.detail << "\n";
  }
  for (const CalibrationRecord& r : session.calibrations()) show_record(r);
}

void run_apply(const CalibrationCommandOptions& o) {
  const CalibrationRecord record = store_of(o).get(o.record_id);
  std::string channel = o.channel;
  // A geometry record belongs to the load cell's mounting (its serial names the bench).
  const bool geometry = record.sensor_kind == "geometry";
  const std::string kind = geometry ? "load_cell" : record.sensor_kind;
  const std::string serial = geometry ? "" : record.sensor_serial;
  {
    const SessionReader session(o.what);
    if (channel.empty()) {
      std::vector<std::string> candidates;
      for (const ChannelInfo& c : session.channels()) {
        if (c.sensor_kind == kind && (serial.empty() || c.sensor_serial == serial)) {
          candidates.push_back(c.name);
        }
      }
      if (candidates.size() != 1) {
        throw std::runtime_error(o.what + ": " + std::to_string(candidates.size()) +
                                 " channels of " + kind + (serial.empty() ? "" : " " + serial) +
                                 " for record " + record.id + "; name one with --channel");
      }
      channel = candidates.front();
    }
    const ChannelInfo& info = session.channel(channel);
    if (info.sensor_kind != kind) {
      throw std::runtime_error(o.what + ": channel " + channel + " is a " + info.sensor_kind +
                               ", record " + record.id + " calibrates a " + kind);
    }
    if (!serial.empty() && info.sensor_serial != serial) {
      throw std::runtime_error(o.what + ": channel " + channel + " has sensor " +
                               info.sensor_serial + ", record " + record.id + " calibrates " +
                               record.sensor_serial);
    }
  }
  const std::string previous = apply_calibration(o.what, channel, record);
  std::cout << o.what << ": channel " << channel << " now uses " << record.id
            << (geometry ? " for its geometry" : "") << " (was "
            << (previous.empty() ? "none" : previous) << "); raw samples unchanged\n";
}

void run_certificate(const CalibrationCommandOptions& o) {
  check_output_file(o.out, {}, o.overwrite);  // docs/output-files.md
  cal::write_certificate(o.out, store_of(o).get(o.what));
  std::cerr << "wrote " << o.out << "\n";
}

}  // namespace

void add_calibration_command(CLI::App& app, Action& action) {
  CLI::App* calibration =
      app.add_subcommand("calibration",
                         "Show calibration records (the store or a session's), apply one to a "
                         "session, write a certificate");
  calibration->require_subcommand(1);
  auto o = std::make_shared<CalibrationCommandOptions>();
  auto store_option = [o](CLI::App* command) {
    command->add_option("--calibrations", o->store_dir,
                        "Calibration store directory (default: $DOORBENCH_CALIBRATIONS, else "
                        "./calibrations)");
  };
  CLI::App* show = calibration->add_subcommand(
      "show",
      "No argument: list the store. An id: that record. A session (.h5): the records "
      "its channels use, calibration events and inclinometer range warnings");
  show->add_option("WHAT", o->what, "A record id or a session file");
  store_option(show);
  show->callback([o, &action] { action = [o] { run_show(*o); }; });

  CLI::App* apply = calibration->add_subcommand(
      "apply", "Make a session's channel use a record of the store (raw samples never change)");
  apply->add_option("SESSION", o->what, "Session file (HDF5)")->required();
  apply->add_option("--record", o->record_id, "The record's id in the store")->required();
  apply->add_option("--channel", o->channel, "The channel (default: the one of that sensor)");
  store_option(apply);
  apply->callback([o, &action] { action = [o] { run_apply(*o); }; });

  CLI::App* certificate = calibration->add_subcommand(
      "certificate", "Write a record's calibration certificate (HTML; print it to PDF)");
  certificate->add_option("ID", o->what, "The record's id in the store")->required();
  certificate->add_option("--out", o->out, "The HTML file to write")->required();
  certificate->add_flag("--overwrite", o->overwrite, "Replace an existing --out file");
  store_option(certificate);
  certificate->callback([o, &action] { action = [o] { run_certificate(*o); }; });
}

}  // namespace doorbench::app
