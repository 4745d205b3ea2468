// Raw channels to physical units on import (acquisition/session/import_units.h; docs/tdms.md
// and docs/csv-format.md "Raw channels"): a DAQmx-layout file whose bridge is logged in
// volts imports to newtons through a calibration record of the store, a record's file, or
// --scale; the session keeps the volts as its raw values and names the record, and its
// physical values are raw × gain + offset to 1e-12. The same for a CSV's force_V column.
// The mistakes a user makes are answered word for word.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "acquisition/rig/calibration_store.h"
#include "acquisition/session/import_units.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_file.h"
#include "acquisition/session/tdms.h"
#include "core/number_format.h"
#include "core/units.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/tdms_writer.h"

namespace doorbench {
namespace {

using namespace testing::tdms;

constexpr int kVoltSamples = 64;
constexpr double kGainNPerV = 98.0665 * 2.0 / 3.0;  // a 200 N cell at 3 V full scale
constexpr double kOffsetN = -0.8125;

std::int16_t bridge_counts(int k) {
  return static_cast<std::int16_t>(std::lround(9000.0 * std::sin(0.09 * k) + 200.0));
}
std::int32_t encoder_counts(int k) {
  return static_cast<std::int32_t>(std::lround(40000.0 * (1.0 - std::cos(0.05 * k))));
}
// The bridge's volts as DAQmx scales its counts (Linear, the unit Volts).
double bridge_volts(int k) {
  return 3.0517578125e-4 * bridge_counts(k) - 0.0015;
}

// DAQmx logging's layout (ToC 0xAE): one raw buffer of 8 bytes a sample, the bridge's I16 at
// 0 and the encoder's I32 at 4; the bridge in Volts, the encoder in rad.
std::vector<std::uint8_t> volts_file(const std::string& bridge_unit) {
  const std::uint32_t toc =
      kTocMetaData | kTocNewObjList | kTocRawData | kTocInterleavedData | kTocDAQmxRawData;
  const std::vector<Property> bridge = {
      text_property("unit_string", bridge_unit),
      double_property("wf_increment", 0.001),
      text_property("NI_Scaling_Status", "unscaled"),
      i32_property("NI_Number_Of_Scales", 2),
      text_property("NI_Scale[1]_Scale_Type", "Linear"),
      double_property("NI_Scale[1]_Linear_Slope", 3.0517578125e-4),
      double_property("NI_Scale[1]_Linear_Y_Intercept", -0.0015),
      i32_property("NI_Scale[1]_Linear_Input_Source", 0)};
  const std::vector<Property> encoder = {text_property("unit_string", "rad"),
                                         double_property("wf_increment", 0.001),
                                         text_property("NI_Scaling_Status", "unscaled"),
                                         i32_property("NI_Number_Of_Scales", 2),
                                         text_property("NI_Scale[1]_Scale_Type", "Linear"),
                                         double_property("NI_Scale[1]_Linear_Slope", 2.5e-5),
                                         double_property("NI_Scale[1]_Linear_Y_Intercept", 0.0),
                                         i32_property("NI_Scale[1]_Linear_Input_Source", 0)};
  const std::vector<Object> objects = {
      daqmx_channel("/'Dev1'/'Bridge'", kVoltSamples, {{3, 0, 0, 0}}, {8}, false, bridge),
      daqmx_channel("/'Dev1'/'Encoder'", kVoltSamples, {{5, 0, 4, 0}}, {8}, false, encoder)};
  Bytes raw;
  for (int k = 0; k < kVoltSamples; ++k) {
    raw.put(bridge_counts(k));
    raw.put<std::uint16_t>(0);
    raw.put(encoder_counts(k));
  }
  return segment(toc, objects, raw).data;
}

void write_bytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

doorbench::CalibrationRecord load_cell_record() {
  doorbench::CalibrationRecord record;
  record.id = "load_cell-LC445-0193-v2";
  record.version = 2;
  record.sensor_kind = "load_cell";
  record.sensor_serial = "LC445-0193";
  record.input_unit = "V";
  record.unit = "N";
  record.coefficients = {kOffsetN, kGainNPerV};
  record.method = "multi-point";
  return record;
}

// The session's force channel: its raw values are the file's volts, its record is `id`, and
// its physical values are raw × gain + offset to 1e-12 relative.
void check_force_in_newtons(const std::filesystem::path& session_path, const std::string& id,
                            double gain, double offset) {
  const SessionReader session(session_path);
  const ChannelInfo& force = session.channel("force");
  CHECK(force.calibration_id == id);
  CHECK(force.raw_unit == "V");
  CHECK(force.unit == "N");
  bool named = false;
  for (const doorbench::CalibrationRecord& record : session.calibrations()) {
    named = named || record.id == id;
  }
  CHECK(named);
  const ChannelSlice slice = session.read("force");
  const std::vector<double> newtons = session.physical("force", slice);
  REQUIRE(slice.raw.size() == kVoltSamples);
  for (int k = 0; k < kVoltSamples; ++k) {
    INFO("sample " << k);
    CHECK(slice.raw[k] == Approx(bridge_volts(k)).epsilon(1e-12).margin(1e-15));
    const double expected = bridge_volts(k) * gain + offset;
    CHECK(std::abs(newtons[k] - expected) <= 1e-12 * std::abs(expected));
  }
}

// A channel of doubles in group Lab as LabVIEW writes one: its values and its unit, no timing.
Object lab_channel(const std::string& name, const std::string& unit, std::uint64_t count) {
  Object channel;
  channel.raw = Object::kNew;
  channel.path = "/'Lab'/'" + name + "'";
  channel.type = kDouble;
  channel.count = count;
  channel.properties = {text_property("unit_string", unit)};
  return channel;
}

// The session's force samples: `count` of them, `interval_s` apart from the first to 1 ns.
void check_sample_times(const std::filesystem::path& session_path, std::size_t count,
                        double interval_s) {
  const ChannelSlice force = SessionReader(session_path).read("force");
  REQUIRE(force.time_s.size() == count);
  for (std::size_t k = 0; k < count; ++k) {
    CHECK(std::abs(force.time_s[k] - force.time_s[0] - interval_s * static_cast<double>(k)) <=
          1e-9);
  }
}

// Runs doorbench in `dir`, so that names in its messages are as given.
std::string units_dir_env(const testing::TempDir& dir) {
  return "env -C '" + dir.path.string() + "'";
}

}  // namespace

TEST_CASE("Import units: a DAQmx file in volts imports to newtons through a record",
          "[tdms][daqmx][cli]") {
  const testing::TempDir dir("import_units");
  write_bytes(dir / "volts.tdms", volts_file("Volts"));
  write_bytes(dir / "v.tdms", volts_file("V"));
  const doorbench::CalibrationStore store(dir / "calibrations");
  store.add(load_cell_record());
  const std::string map = " --map force=Dev1/Bridge,angle=Dev1/Encoder ";

  // Without a conversion: refused, saying what would convert it.
  testing::DoorbenchRun run = testing::run_doorbench_shell("import v.tdms" + map + "--out plain.h5",
                                                           dir, units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: v.tdms: force: channel Dev1/Bridge is in 'V', not N (convert it: "
        "--calibration force=RECORD or --scale force=GAIN[,OFFSET]; or map it as an extra "
        "column whose name ends in its unit); the file's channels: Dev1/Bridge, Dev1/Encoder\n");

  // A record of the store (./calibrations, the working directory's).
  run = testing::run_doorbench_shell(
      "import v.tdms" + map + "--calibration force=load_cell-LC445-0193-v2 --out store.h5", dir,
      units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.err ==
        "wrote store.h5: 64 samples\n"
        "  force_N: raw V kept, physical through load_cell-LC445-0193-v2 (multi-point)\n");
  check_force_in_newtons(dir / "store.h5", "load_cell-LC445-0193-v2", kGainNPerV, kOffsetN);

  // The record's file.
  run = testing::run_doorbench_shell(
      "import v.tdms" + map +
          "--calibration force=calibrations/load_cell-LC445-0193-v2.json --out file.h5",
      dir, units_dir_env(dir));
  REQUIRE(run.status == 0);
  check_force_in_newtons(dir / "file.h5", "load_cell-LC445-0193-v2", kGainNPerV, kOffsetN);

  // A scale given by hand.
  run = testing::run_doorbench_shell(
      "import v.tdms" + map + "--scale force=65.377,-0.8125 --out scale.h5", dir,
      units_dir_env(dir));
  REQUIRE(run.status == 0);
  check_force_in_newtons(dir / "scale.h5", "scale-force", 65.377, -0.8125);
  const SessionReader scaled(dir / "scale.h5");
  const std::vector<doorbench::CalibrationRecord> records = scaled.calibrations();
  REQUIRE(records.size() == 1);
  CHECK(records[0].method == "doorbench import --scale force=65.377,-0.8125");
  CHECK(records[0].input_unit == "V");

  // The record takes V; a channel in 'Volts' says so and is refused, not guessed.
  run = testing::run_doorbench_shell(
      "import volts.tdms" + map + "--calibration force=load_cell-LC445-0193-v2 --out x.h5", dir,
      units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: volts.tdms: force: channel Dev1/Bridge is in 'Volts', not V (--calibration "
        "force=load_cell-LC445-0193-v2); the file's channels: Dev1/Bridge, Dev1/Encoder\n");
  // A record that gives another unit, and one that is not there.
  run = testing::run_doorbench_shell(
      "import v.tdms" + map + "--calibration angle=load_cell-LC445-0193-v2 --out x.h5", dir,
      units_dir_env(dir));
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --calibration angle=load_cell-LC445-0193-v2: record load_cell-LC445-0193-v2 "
        "gives N, not rad (angle is in rad) (see doorbench import --help)\n");
  run = testing::run_doorbench_shell("import v.tdms" + map + "--calibration force=nope --out x.h5",
                                     dir, units_dir_env(dir));
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --calibration force=nope: no file nope and no record nope in the "
        "calibration store " +
            (dir / "calibrations").string() +
            " (its records: load_cell-LC445-0193-v2) (see doorbench import --help)\n");
  run = testing::run_doorbench_shell("import v.tdms" + map + "--scale force=abc --out x.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --scale item 'force=abc' is not TARGET=GAIN[,OFFSET] (e.g. "
        "force=98.1,-0.5) (see doorbench import --help)\n");
  CHECK(!std::filesystem::exists(dir / "x.h5"));
}

TEST_CASE("Import units: a CSV's raw column imports through a record or a scale", "[csv][cli]") {
  const testing::TempDir dir("import_units_csv");
  std::string csv = "# source: bench logger\ntime_s,force_V,angle_rad\n";
  for (int k = 0; k < kVoltSamples; ++k) {
    csv += format_csv_number(0.001 * k) + "," + format_csv_number(bridge_volts(k)) + "," +
           format_csv_number(2.5e-5 * encoder_counts(k)) + "\n";
  }
  dir.write("run.csv", csv);
  const doorbench::CalibrationStore store(dir / "store");
  store.add(load_cell_record());
  testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import run.csv --calibrations store --calibration force=load_cell-LC445-0193-v2 --out r.h5",
      dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  check_force_in_newtons(dir / "r.h5", "load_cell-LC445-0193-v2", kGainNPerV, kOffsetN);
  run = testing::run_doorbench_shell("import run.csv --scale force=65.377,-0.8125 --out s.h5", dir,
                                     units_dir_env(dir));
  REQUIRE(run.status == 0);
  check_force_in_newtons(dir / "s.h5", "scale-force", 65.377, -0.8125);
  // The column the record needs is not there.
  dir.write("n.csv", "time_s,force_N,angle_rad\n0,1,0\n0.001,2,0\n");
  run = testing::run_doorbench_shell(
      "import n.csv --calibrations store --calibration force=load_cell-LC445-0193-v2 --out t.h5",
      dir, units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: n.csv:1: --calibration force=load_cell-LC445-0193-v2: no column "
        "force_V (the raw force); the columns: time_s, force_N, angle_rad\n");
  // Without a conversion a CSV's force_V is not a force.
  run = testing::run_doorbench_shell("import run.csv --out u.h5", dir, units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: run.csv:2: header lacks required column force_N; the file's columns: time_s, "
        "force_V, angle_rad (--map time=COLUMN,force=COLUMN,angle=COLUMN names a file's own "
        "columns: docs/csv-format.md)\n");
}

TEST_CASE("Import: the units a CSV column's name states", "[csv]") {
  CHECK(unit_stated_in_name("Force (V)") == "V");
  CHECK(unit_stated_in_name("Rate [deg/s]") == "deg/s");
  CHECK(unit_stated_in_name("Time ( s )") == "s");
  CHECK(unit_stated_in_name("Force") == "");
  CHECK(unit_stated_in_name("Force (V) filtered") == "");
  CHECK(unit_stated_in_name("force_V") == "");
  CHECK(unit_stated_in_name(")") == "");
}

// The conversion a stated unit implies, shared by a CSV column's name and a TDMS channel's
// unit_string: force, angle and rate only, and only units with an exact factor.
TEST_CASE("Import: the conversion a stated unit implies", "[csv][tdms]") {
  const auto angle = stated_unit_conversion("angle", "deg", "--map angle=Angle (deg)");
  REQUIRE(angle);
  CHECK(angle->target == "angle");
  CHECK(angle->gain == kRadPerDeg);
  CHECK(angle->offset == 0.0);
  CHECK(angle->from_stated_unit);
  CHECK_FALSE(angle->record);
  CHECK(angle->given == "--map angle=Angle (deg)");
  const auto rate = stated_unit_conversion("rate", "rpm", "rate=/'g'/'rate'");
  REQUIRE(rate);
  CHECK(rate->gain == Approx(2.0 * std::numbers::pi / 60.0).epsilon(1e-15));
  const auto force = stated_unit_conversion("force", "kN", "force");
  REQUIRE(force);
  CHECK(force->gain == 1000.0);
  CHECK_FALSE(stated_unit_conversion("force", "V", "force"));      // needs a record
  CHECK_FALSE(stated_unit_conversion("angle", "rad", "angle"));    // already the target's
  CHECK_FALSE(stated_unit_conversion("time", "ms", "time"));       // the time is scaled
  CHECK_FALSE(stated_unit_conversion("incl_deg", "deg", "incl"));  // an extra keeps its unit
}

// A logger's own CSV: its own column names with units in parentheses, the force in volts and
// the angle in degrees, a column nobody maps. --map names the columns and --calibration and
// --scale make them physical; the mistakes are answered word for word with the file's columns.
TEST_CASE("Import: a CSV with its own column names imports through --map", "[csv][cli]") {
  const testing::TempDir dir("import_csv_map");
  std::string csv = "Time (s),Force (V),Angle [deg],Temperature (C)\n";
  for (int k = 0; k < kVoltSamples; ++k) {
    csv += format_csv_number(0.001 * k) + "," + format_csv_number(bridge_volts(k)) + "," +
           format_csv_number(1e-3 * encoder_counts(k)) + ",21.5\n";
  }
  dir.write("log.csv", csv);
  const doorbench::CalibrationStore store(dir / "store");
  store.add(load_cell_record());
  const std::string map = " --map 'time=Time (s),force=Force (V),angle=Angle [deg]'";
  const std::string degrees = " --scale angle=" + format_csv_number(kRadPerDeg);
  testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import log.csv --calibrations store --calibration force=load_cell-LC445-0193-v2" + map +
          degrees + " --out r.h5",
      dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  check_force_in_newtons(dir / "r.h5", "load_cell-LC445-0193-v2", kGainNPerV, kOffsetN);
  const SessionReader session(dir / "r.h5");
  CHECK(session.channel("angle").raw_unit == "deg");
  const ChannelSlice angle = session.read("angle");
  const std::vector<double> radians = session.physical("angle", angle);
  REQUIRE(radians.size() == kVoltSamples);
  for (int k = 0; k < kVoltSamples; ++k) {
    const double expected = 1e-3 * encoder_counts(k) * kRadPerDeg;
    CHECK(std::abs(radians[k] - expected) <= 1e-12 * std::abs(expected));
  }
  std::vector<std::string> names;  // the temperature column is not mapped: not imported
  for (const ChannelInfo& channel : session.channels()) names.push_back(channel.name);
  CHECK(names == std::vector<std::string>{"force", "angle"});
  CHECK(session.read_group_attribute("import", "csv_map_force_column") == "Force (V)");
  // --scale on a column that states no unit.
  dir.write("plain.csv", "t (s),Load,Angle (rad)\n0,1,0\n0.001,2,0.001\n");
  run = testing::run_doorbench_shell(
      "import plain.csv --map 'time=t (s),force=Load,angle=Angle (rad)' --scale force=2 --out "
      "p.h5",
      dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(SessionReader(dir / "p.h5").channel("force").raw_unit == "unstated");

  const auto refused = [&](const std::string& options) {
    return testing::run_doorbench_shell("import log.csv" + options + " --out x.h5", dir,
                                        units_dir_env(dir));
  };
  const std::string columns =
      "; the file's columns: Time (s), Force (V), Angle [deg], Temperature (C)\n";
  run = refused(map);
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: log.csv:1: --map force=Force (V): column 'Force (V)' is in 'V', not N "
        "(convert it: --calibration force=RECORD or --scale force=GAIN[,OFFSET]; or map it as "
        "an extra column whose name ends in its unit)" +
            columns);
  run = refused(" --map 'time=Time (s),force=Force (N),angle=Angle [deg]'");
  CHECK(run.err == "doorbench: log.csv:1: --map force=Force (N): no column 'Force (N)'" + columns);
  run = refused(" --map 'time=Time (s),force=Force (V),angle=Force (V)' --scale force=2");
  CHECK(run.err ==
        "doorbench: log.csv:1: --map angle=Force (V): column 'Force (V)' is mapped to force "
        "already (one column, one target)" +
            columns);
  run = refused(
      " --map 'time=Time (s),force=Force (V),angle=Angle [deg]' --calibrations store "
      "--calibration angle=load_cell-LC445-0193-v2");
  CHECK(run.status == 2);
  run = refused(" --map 'time=Temperature (C),force=Force (V),angle=Angle [deg]' --scale force=2" +
                degrees);
  CHECK(run.err ==
        "doorbench: log.csv:1: --map time=Temperature (C): column 'Temperature (C)' is in 'C', "
        "not s (the time is read in s, ms or us: convert the column)" +
            columns);
  run = refused(" --map 'time=Time (s),force'");
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --map item 'force' is not TARGET=COLUMN (e.g. force=Force (N)); the file's "
        "columns: Time (s), Force (V), Angle [deg], Temperature (C) (see doorbench import "
        "--help)\n");
  run = refused(" --map 'force=Force (V),angle=Angle [deg]' --scale force=2" + degrees);
  CHECK(run.err ==
        "doorbench: log.csv:1: header lacks required column time_s; the file's columns: Time "
        "(s), Force (V), Angle [deg], Temperature (C) (--map time=COLUMN,force=COLUMN,"
        "angle=COLUMN names a file's own columns: docs/csv-format.md)\n");
  // A key of the file's own metadata that import writes itself (the column --map took).
  dir.write("keyed.csv", "# map_force_column: Load\n" + csv);
  run = testing::run_doorbench_shell(
      "import keyed.csv" + map + " --scale force=2" + degrees + " --out x.h5", dir,
      units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: keyed.csv: metadata key 'map_force_column' is one import writes itself; "
        "rename the file's key\n");
  for (const auto& entry : std::filesystem::directory_iterator(dir.path)) {
    CHECK(entry.path().filename().string().rfind("x.h5", 0) == std::string::npos);  // no partial
  }
}

// A logger's own units that are exact multiples of the session's are converted, not refused:
// the time in ms, the force in kN, the angle in degrees and the rate in deg/s or rpm. The
// session keeps the raw values in the stated unit under a unit-TARGET record; an explicit
// --scale still wins over the stated unit.
TEST_CASE("Import: a --map column in ms, kN, deg, deg/s or rpm is converted exactly",
          "[csv][cli]") {
  const testing::TempDir dir("import_csv_stated_units");
  constexpr int kSamples = 50;
  const auto rate_in_rpm = [](int k) { return 3.0 + 0.5 * k; };
  std::string csv = "Zeit (ms),Kraft (kN),Winkel (deg),Drehrate (deg/s),Motor (rpm)\n";
  for (int k = 0; k < kSamples; ++k) {
    csv += format_csv_number(2.0 * k) + "," + format_csv_number(1e-3 * bridge_volts(k)) + "," +
           format_csv_number(0.25 * k) + "," + format_csv_number(10.0 - 0.1 * k) + "," +
           format_csv_number(rate_in_rpm(k)) + "\n";
  }
  dir.write("log.csv", csv);
  testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import log.csv --map 'time=Zeit (ms),force=Kraft (kN),angle=Winkel (deg),rate=Drehrate "
      "(deg/s)' --out a.h5",
      dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Catch::Contains("angle_rad: raw deg kept, physical through unit-angle "
                                      "(doorbench import --map angle=Winkel (deg), the unit its "
                                      "name states)"));
  {
    const SessionReader session(dir / "a.h5");
    const ChannelSlice angle = session.read("angle");
    REQUIRE(angle.time_s.size() == kSamples);
    CHECK(session.channel("angle").raw_unit == "deg");
    CHECK(session.channel("angle").calibration_id == "unit-angle");
    CHECK(session.channel("force").raw_unit == "kN");
    CHECK(session.channel("rate").raw_unit == "deg/s");
    const std::vector<double> radians = session.physical("angle", angle);
    const std::vector<double> newtons = session.physical("force", session.read("force"));
    const std::vector<double> rates = session.physical("rate", session.read("rate"));
    for (int k = 0; k < kSamples; ++k) {
      CHECK(std::abs(angle.time_s[k] - angle.time_s[0] - 2e-3 * k) <= 1e-12);
      CHECK(std::abs(radians[k] - 0.25 * k * kRadPerDeg) <= 1e-12);
      CHECK(std::abs(newtons[k] - bridge_volts(k)) <= 1e-9 * std::abs(bridge_volts(k)) + 1e-12);
      CHECK(std::abs(rates[k] - (10.0 - 0.1 * k) * kRadPerDeg) <= 1e-12);
    }
  }
  // rpm for the rate; an explicit --scale wins over the unit the name states.
  run = testing::run_doorbench_shell(
      "import log.csv --map 'time=Zeit (ms),force=Kraft (kN),rate=Motor (rpm)' --scale force=2 "
      "--out b.h5",
      dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  const SessionReader session(dir / "b.h5");
  CHECK(session.channel("force").calibration_id == "scale-force");
  const std::vector<double> newtons = session.physical("force", session.read("force"));
  const std::vector<double> rates = session.physical("rate", session.read("rate"));
  REQUIRE(rates.size() == kSamples);
  for (int k = 0; k < kSamples; ++k) {
    CHECK(std::abs(newtons[k] - 2e-3 * bridge_volts(k)) <= 1e-12);
    CHECK(std::abs(rates[k] - rate_in_rpm(k) * 2.0 * std::numbers::pi / 60.0) <= 1e-12);
  }
  // A unit that is no exact multiple (a time in minutes, an angle in grads) is still refused.
  dir.write("min.csv", "t (min),F (N),a (grad)\n0,1,0\n1,1,1\n");
  run = testing::run_doorbench_shell(
      "import min.csv --map 'time=t (min),force=F (N),angle=a (grad)' --out c.h5", dir,
      units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: min.csv:1: --map time=t (min): column 't (min)' is in 'min', not s (the time "
        "is read in s, ms or us: convert the column); the file's columns: t (min), F (N), a "
        "(grad)\n");
}

// A logger that stamps each row with its date and time: the --map time column is read as
// seconds since the first row's; a stated zone gives the session's start, none is warned about;
// a column that mixes dates and numbers is refused at its line.
TEST_CASE("Import: a --map time column of dates and times is read as seconds since the first",
          "[csv][cli]") {
  const testing::TempDir dir("import_csv_date_times");
  const auto log = [](const std::string& zone) {
    std::string csv = "Timestamp,Force (N),Angle (rad)\n";
    for (int k = 0; k < 120; ++k) {  // 8 ms apart from 23:58:59.5, across the minute's end
      const int ms = 58 * 60000 + 59500 + 8 * k;
      csv += printf_text("2024-02-29 23:%02d:%02d.%03d", ms / 60000, (ms / 1000) % 60, ms % 1000);
      csv += zone + "," + format_csv_number(1.0 + 0.01 * k) + ",0.1\n";
    }
    return csv;
  };
  dir.write("local.csv", log(""));
  dir.write("zoned.csv", log("+01:00"));
  const std::string map = " --map 'time=Timestamp,force=Force (N),angle=Angle (rad)'";
  testing::DoorbenchRun run = testing::run_doorbench_shell("import local.csv" + map + " --out a.h5",
                                                           dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.err ==
        "wrote a.h5: 120 samples\n"
        "  time_s: dates and times read as seconds since the first, 2024-02-29T23:58:59.500000 "
        "(no time zone stated)\n"
        "warning: the time column states no time zone, so the session's start is the import's "
        "time; give the recording's with --start-time (ISO 8601 UTC)\n");
  check_sample_times(dir / "a.h5", 120, 0.008);
  CHECK(
      SessionReader(dir / "a.h5").read_group_attribute("import", "csv_map_time_first_date_time") ==
      "2024-02-29T23:58:59.500000");
  run = testing::run_doorbench_shell("import zoned.csv" + map + " --out b.h5", dir,
                                     units_dir_env(dir));
  REQUIRE(run.status == 0);
  CHECK(run.err.find("warning") == std::string::npos);
  CHECK(SessionReader(dir / "b.h5").metadata().start_time_utc == "2024-02-29T22:58:59.500000Z");
  // --start-time is the start whatever the column says, and silences the warning.
  run = testing::run_doorbench_shell(
      "import local.csv" + map + " --start-time 2024-02-29T22:59:59Z --out c.h5", dir,
      units_dir_env(dir));
  REQUIRE(run.status == 0);
  CHECK(run.err.find("warning") == std::string::npos);
  // A spreadsheet's ';' file with decimal commas keeps the '.' of the dates' fractions.
  std::string european = log("");
  std::replace(european.begin(), european.end(), ',', ';');
  for (std::size_t line = european.find('\n'); line != std::string::npos;
       line = european.find('\n', line + 1)) {
    const std::size_t end = european.find('\n', line + 1);
    const std::size_t first_field_end = european.find(';', line);
    for (std::size_t at = first_field_end; at < end && at != std::string::npos; ++at) {
      if (european[at] == '.') european[at] = ',';  // the numbers' decimal points, not the dates'
    }
  }
  dir.write("european.csv", european);
  run = testing::run_doorbench_shell(
      "import european.csv" + map + " --separator semicolon --decimal-comma --out f.h5", dir,
      units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(SessionReader(dir / "f.h5").read("force").time_s.size() == 120);
  // A number among dates, or a date without the first row's zone, is refused at its line.
  std::string mixed = log("");
  mixed.replace(mixed.find("2024-02-29 23:58:59.516"), 23, "0.016");
  dir.write("mixed.csv", mixed);
  run = testing::run_doorbench_shell("import mixed.csv" + map + " --out d.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: mixed.csv:4: column Timestamp: '0.016' is not a date and time without a time "
        "zone as the first row's (YYYY-MM-DD hh:mm:ss.fff)\n");
  std::string zones = log("Z");
  zones.replace(zones.find("23:58:59.508Z"), 13, "23:58:59.508");
  dir.write("zones.csv", zones);
  run = testing::run_doorbench_shell("import zones.csv" + map + " --out e.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.err ==
        "doorbench: zones.csv:3: column Timestamp: '2024-02-29 23:58:59.508' is not a date and "
        "time with a time zone (Z or +hh:mm) as the first row's (YYYY-MM-DD hh:mm:ss.fff)\n");
}

// A logger that stamps each row with the time of the day only: read as seconds since the first
// row's, across midnight; the start is the import's time unless given, and said so.
TEST_CASE("Import: a --map time column of times of the day is read across midnight", "[csv][cli]") {
  const testing::TempDir dir("import_csv_times_of_day");
  std::string csv = "Time,Force (N),Angle (rad)\n";
  for (int k = 0; k < 100; ++k) {  // 20 ms apart from 23:59:59.000, across midnight at k = 50
    const int ms = (86399000 + 20 * k) % 86400000;
    csv += printf_text("%02d:%02d:%02d.%03d,%s,0.1\n", ms / 3600000, (ms / 60000) % 60,
                       (ms / 1000) % 60, ms % 1000, format_csv_number(1.0 + 0.01 * k).c_str());
  }
  dir.write("clock.csv", csv);
  const std::string map = " --map 'time=Time,force=Force (N),angle=Angle (rad)'";
  testing::DoorbenchRun run = testing::run_doorbench_shell("import clock.csv" + map + " --out a.h5",
                                                           dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.err ==
        "wrote a.h5: 100 samples\n"
        "  time_s: times of the day read as seconds since the first, 23:59:59.000000 (no date "
        "stated)\n"
        "warning: the time column states no date, so the session's start is the import's time; "
        "give the recording's with --start-time (ISO 8601 UTC)\n");
  check_sample_times(dir / "a.h5", 100, 0.02);
  // A date among times of the day is refused at its line, as is a time of the day among dates.
  struct Refused {
    std::string file, cell, replacement, message;
  };
  for (const Refused& refused :
       {Refused{"mixed.csv", "23:59:59.020", "2024-05-02 23:59:59.020",
                "mixed.csv:3: column Time: '2024-05-02 23:59:59.020' is not a time of the day "
                "without a date as the first row's (hh:mm:ss.fff)"},
        Refused{"dated.csv", "23:59:59.000", "2024-05-02 23:59:59.000",
                "dated.csv:3: column Time: '23:59:59.020' is not a date and time without a "
                "time zone as the first row's (YYYY-MM-DD hh:mm:ss.fff)"}}) {
    std::string text = csv;
    text.replace(text.find(refused.cell), refused.cell.size(), refused.replacement);
    dir.write(refused.file, text);
    run = testing::run_doorbench_shell("import " + refused.file + map + " --out b.h5", dir,
                                       units_dir_env(dir));
    CHECK(run.status == 1);
    CHECK(run.err == "doorbench: " + refused.message + "\n");
  }
  CHECK(!std::filesystem::exists(dir / "b.h5"));
}

// What import tells of a date-time column's clock comes from the recording itself: the zone the
// column states, or a start the file's own metadata gives, makes the start known.
TEST_CASE("Import: imported_date_times says whether the recording states its start", "[csv]") {
  const testing::TempDir dir("import_date_time_start");
  const auto read = [&dir](const std::string& metadata, const std::string& zone) {
    std::string csv = metadata + "Timestamp,Force (N),Angle (rad)\n";
    for (int k = 0; k < 10; ++k) {
      csv += printf_text("2024-05-02 09:30:00.%03d%s,1.0,0.1\n", 10 * k, zone.c_str());
    }
    dir.write("log.csv", csv);
    return imported_date_times(
        read_csv_import(dir / "log.csv", "time=Timestamp,force=Force (N),angle=Angle (rad)", {}));
  };
  const auto local = read("", "");
  REQUIRE(local);
  CHECK(local->first == "2024-05-02T09:30:00.000000");
  CHECK_FALSE(local->zone_stated);
  CHECK(local->date_stated);
  CHECK(local->start_unknown(false));
  CHECK_FALSE(local->start_unknown(true));
  const auto zoned = read("", "-02:00");
  REQUIRE(zoned);
  CHECK(zoned->first == "2024-05-02T11:30:00.000000Z");
  CHECK(zoned->zone_stated);
  CHECK_FALSE(zoned->start_unknown(false));
  const auto stated = read("# start_time_utc: 2024-05-02T07:30:00Z\n", "");
  REQUIRE(stated);
  CHECK_FALSE(stated->zone_stated);
  CHECK(stated->start_stated);
  CHECK_FALSE(stated->start_unknown(false));
  dir.write("numbers.csv", "time_s,force_N,angle_rad\n0,1,0.1\n0.01,1,0.1\n");
  CHECK_FALSE(imported_date_times(read_csv_import(dir / "numbers.csv", "", {})));
}

// A logger's columns that state no unit are read in the session's units; a door's angle in
// degrees read that way spans more than a turn, and import and fit say so word for word (the fit
// in report.md too), naming the conversion. Stated as (deg), the same column is converted and
// nothing is in doubt.
TEST_CASE("Import: an angle in degrees whose column states no unit is in doubt", "[csv][cli]") {
  const testing::TempDir dir("import_units_in_doubt");
  const std::string simulated = testing::simulate_open_close_csv(dir, "sim.csv", 10.0, 1000.0);
  REQUIRE_FALSE(simulated.empty());
  const Recording door = read_recording_csv(simulated);
  REQUIRE(door.angle_rad);
  std::string plain = "Time,Load,Angle\n";
  std::string stated = "Time,Load,Angle (deg)\n";
  double lowest_deg = 0.0, widest_deg = 0.0;
  for (std::size_t k = 0; k < door.size(); ++k) {
    const double degrees = (*door.angle_rad)[k] / kRadPerDeg;
    lowest_deg = std::min(lowest_deg, degrees);
    widest_deg = std::max(widest_deg, degrees);
    const std::string row = format_csv_number(door.time_s[k]) + "," +
                            format_csv_number(door.force_N[k]) + "," + format_csv_number(degrees) +
                            "\n";
    plain += row;
    stated += row;
  }
  REQUIRE(widest_deg > 60.0);
  dir.write("plain.csv", plain);
  dir.write("stated.csv", stated);
  const std::string doubt =
      "warning: units in doubt: angle_rad spans " + format_significant(lowest_deg, 4) + " to " +
      format_significant(widest_deg, 4) +
      " rad, more than a turn: an angle in degrees read as radians? (import converts it: --scale "
      "angle=" +
      format_significant(kRadPerDeg, 6) + ", or a --map column whose name ends in (deg))";
  testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import plain.csv --map time=Time,force=Load,angle=Angle --out plain.h5", dir,
      units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.err == "wrote plain.h5: " + std::to_string(door.size()) + " samples\n" + doubt + "\n");
  run = testing::run_doorbench_shell("fit plain.h5 --out fit", dir, units_dir_env(dir));
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, Catch::Contains("\n" + doubt + "\n"));
  // The doubt, the likely cause, comes before the samples preprocessing could not use.
  const std::size_t impossible = run.err.find("\nwarning: angle_rad: ");
  REQUIRE(impossible != std::string::npos);
  CHECK_THAT(run.err.substr(impossible, run.err.find('\n', impossible + 1) - impossible),
             Catch::Contains(" physically impossible samples (|value| > "));
  CHECK(run.err.find(doubt) < impossible);
  std::ifstream report(dir / "fit" / "report.md");
  const std::string report_text((std::istreambuf_iterator<char>(report)),
                                std::istreambuf_iterator<char>());
  CHECK_THAT(report_text, Catch::Contains(doubt));

  run = testing::run_doorbench_shell(
      "import stated.csv --map 'time=Time,force=Load,angle=Angle (deg)' --out stated.h5", dir,
      units_dir_env(dir));
  REQUIRE(run.status == 0);
  CHECK_THAT(run.err, !Catch::Contains("units in doubt"));
}

// A spreadsheet's export in a European locale (semicolons, decimal commas, CRLF) and a LabVIEW
// spreadsheet file (tabs) of the same log import to the same session as its comma file.
TEST_CASE("Import: semicolon and tab files import as their comma file does", "[csv][cli]") {
  const testing::TempDir dir("import_csv_dialects");
  std::string comma = "Time (s),Force (V),Angle (rad)\n";
  std::string semicolon = "Time (s);Force (V);Angle (rad)\r\n";
  std::string tab = "Time (s)\tForce (V)\tAngle (rad)\n";
  for (int k = 0; k < kVoltSamples; ++k) {
    const std::string cells[] = {format_csv_number(0.001 * k), format_csv_number(bridge_volts(k)),
                                 format_csv_number(2.5e-5 * encoder_counts(k))};
    comma += cells[0] + "," + cells[1] + "," + cells[2] + "\n";
    tab += cells[0] + "\t" + cells[1] + "\t" + cells[2] + "\n";
    for (int c = 0; c < 3; ++c) {
      std::string cell = cells[c];
      std::replace(cell.begin(), cell.end(), '.', ',');
      semicolon += cell + (c < 2 ? ";" : "\r\n");
    }
  }
  dir.write("log.csv", comma);
  dir.write("log-it.csv", semicolon);
  dir.write("log.txt", tab);
  const std::string map =
      " --map 'time=Time (s),force=Force (V),angle=Angle (rad)' --scale force=65.377,-0.8125";
  for (const auto& [file, options] : std::vector<std::pair<std::string, std::string>>{
           {"log.csv", ""},
           {"log-it.csv", " --separator semicolon --decimal-comma"},
           {"log.txt", " --separator tab"}}) {
    const testing::DoorbenchRun run = testing::run_doorbench_shell(
        "import " + file + options + map + " --out " + file + ".h5", dir, units_dir_env(dir));
    INFO(file << ": " << run.err);
    REQUIRE(run.status == 0);
    check_force_in_newtons(dir / (file + ".h5"), "scale-force", 65.377, -0.8125);
    const SessionReader session(dir / (file + ".h5"));
    const std::vector<double> angle = session.physical("angle", session.read("angle"));
    REQUIRE(angle.size() == kVoltSamples);
    for (int k = 0; k < kVoltSamples; ++k) CHECK(angle[k] == 2.5e-5 * encoder_counts(k));
  }
  const testing::DoorbenchRun wrong =
      testing::run_doorbench_shell("import log-it.csv --out x.h5", dir, units_dir_env(dir));
  CHECK(wrong.status == 1);
  CHECK(wrong.err ==
        "doorbench: log-it.csv:1: column 1 name 'Time (s);Force (V);Angle (rad)' contains ';' or "
        "a tab (fields must be separated by commas; doorbench import reads other separators with "
        "--separator)\n");
}

// A TDMS channel's unit_string in DAQmx's spelling (Newtons, Degrees, RPM) or a multiple of the
// target's unit is converted exactly, as a CSV column's stated unit is; any other is refused.
TEST_CASE("Import: a TDMS channel in Degrees, RPM or ms is converted exactly", "[tdms][cli]") {
  const testing::TempDir dir("import_tdms_stated_units");
  constexpr int kSamples = 40;
  const auto lab_file = [](const std::vector<std::pair<std::string, std::string>>& channels) {
    std::vector<Object> objects;
    for (const auto& [name, unit] : channels) {
      objects.push_back(lab_channel(name, unit, kSamples));
    }
    Bytes raw;
    for (int k = 0; k < kSamples; ++k) raw.put(2.5 * k);                   // Time
    for (int k = 0; k < kSamples; ++k) raw.put(10.0 * std::sin(0.2 * k));  // Force
    for (int k = 0; k < kSamples; ++k) raw.put(1.5 * k);                   // Angle
    for (int k = 0; k < kSamples; ++k) raw.put(6.0);                       // Rate
    return segment(kTocMetaData | kTocNewObjList | kTocRawData, objects, raw).data;
  };
  write_bytes(
      dir / "daqmx.tdms",
      lab_file({{"Time", "ms"}, {"Force", "Newtons"}, {"Angle", "Degrees"}, {"Rate", "RPM"}}));
  const std::string map = " --map time=Lab/Time,force=Lab/Force,angle=Lab/Angle,rate=Lab/Rate ";
  testing::DoorbenchRun run = testing::run_doorbench_shell("import daqmx.tdms" + map + "--out a.h5",
                                                           dir, units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  {
    const SessionReader session(dir / "a.h5");
    const ChannelSlice force = session.read("force");
    REQUIRE(force.time_s.size() == kSamples);
    const std::vector<double> angle = session.physical("angle", session.read("angle"));
    const std::vector<double> rate = session.physical("rate", session.read("rate"));
    for (int k = 0; k < kSamples; ++k) {
      CHECK(force.time_s[k] == Approx(2.5e-3 * k).margin(1e-15));
      CHECK(force.raw[k] == 10.0 * std::sin(0.2 * k));
      CHECK(angle[k] == Approx(1.5 * k * kRadPerDeg).epsilon(1e-14).margin(1e-16));
      CHECK(rate[k] == Approx(6.0 * 2.0 * std::numbers::pi / 60.0).epsilon(1e-14));
    }
    CHECK(session.channel("angle").calibration_id == "unit-angle");
    CHECK(session.channel("angle").raw_unit == "Degrees");
    CHECK(session.channel("rate").calibration_id == "unit-rate");
    CHECK(session.channel("force").calibration_id.empty());
  }
  // A unit that is no multiple of the target's is refused, as before; so is a time in minutes.
  write_bytes(dir / "volts.tdms",
              lab_file({{"Time", "s"}, {"Force", "Volts"}, {"Angle", "Degrees"}, {"Rate", "RPM"}}));
  run = testing::run_doorbench_shell("import volts.tdms" + map + "--out b.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: volts.tdms: force: channel Lab/Force is in 'Volts', not N (convert it: "
        "--calibration force=RECORD or --scale force=GAIN[,OFFSET]; or map it as an extra column "
        "whose name ends in its unit); the file's channels: Lab/Time, Lab/Force, Lab/Angle, "
        "Lab/Rate\n");
  write_bytes(dir / "minutes.tdms",
              lab_file({{"Time", "min"}, {"Force", "N"}, {"Angle", "rad"}, {"Rate", "rad/s"}}));
  run = testing::run_doorbench_shell("import minutes.tdms" + map + "--out b.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: minutes.tdms: time: channel Lab/Time is in 'min', not s (the time is read in "
        "s, ms or us); the file's channels: Lab/Time, Lab/Force, Lab/Angle, Lab/Rate\n");
  // A --scale given for the target wins over the unit the channel states.
  run = testing::run_doorbench_shell("import daqmx.tdms" + map + "--scale angle=0.5 --out c.h5",
                                     dir, units_dir_env(dir));
  REQUIRE(run.status == 0);
  CHECK(SessionReader(dir / "c.h5").channel("angle").calibration_id == "scale-angle");
  CHECK(!std::filesystem::exists(dir / "b.h5"));
}

TEST_CASE("Import: a TDMS file without timing imports with --rate-hz and --start-time",
          "[tdms][cli]") {
  const testing::TempDir dir("import_rate");
  // As LabVIEW writes a channel without waveform timing: values, a unit, no wf_increment.
  const auto lab_file = [](bool with_increment) {
    std::vector<Object> objects;
    for (const auto& [name, unit] : {std::pair{"Force", "N"}, std::pair{"Angle", "rad"}}) {
      Object channel = lab_channel(name, unit, 50);
      if (with_increment) channel.properties.push_back(double_property("wf_increment", 0.001));
      objects.push_back(channel);
    }
    Bytes raw;
    for (int k = 0; k < 50; ++k) raw.put(10.0 * std::sin(0.2 * k));
    for (int k = 0; k < 50; ++k) raw.put(0.01 * k);
    return segment(kTocMetaData | kTocNewObjList | kTocRawData, objects, raw).data;
  };
  write_bytes(dir / "lab.tdms", lab_file(false));
  write_bytes(dir / "timed.tdms", lab_file(true));
  const std::string map = " --map force=Lab/Force,angle=Lab/Angle ";
  testing::DoorbenchRun run =
      testing::run_doorbench_shell("import lab.tdms" + map + "--out a.h5", dir, units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: lab.tdms: force: channel Lab/Force has no wf_increment > 0 to give the time "
        "(give its rate, --rate-hz R, or map a time channel, time=GROUP/CHANNEL); the file's "
        "channels: Lab/Force, Lab/Angle\n");
  run = testing::run_doorbench_shell(
      "import lab.tdms" + map + "--rate-hz 200 --start-time 2019-03-04T10:20:30Z --out a.h5", dir,
      units_dir_env(dir));
  INFO(run.err);
  REQUIRE(run.status == 0);
  const SessionReader session(dir / "a.h5");
  CHECK(session.metadata().start_time_utc == "2019-03-04T10:20:30Z");
  CHECK(session.channel("force").sample_rate_hz == 200.0);
  const ChannelSlice slice = session.read("force");
  REQUIRE(slice.time_s.size() == 50);
  for (int k = 0; k < 50; ++k) CHECK(slice.time_s[k] == k / 200.0);
  // A rate that contradicts the file's, a time given twice, a start that is no time.
  run = testing::run_doorbench_shell("import timed.tdms" + map + "--rate-hz 500 --out b.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: timed.tdms: force: --rate-hz 500 contradicts channel Lab/Force's "
        "wf_increment 0.001 s (1000 Hz); the file's channels: Lab/Force, Lab/Angle\n");
  run = testing::run_doorbench_shell("import lab.tdms" + map + "--start-time 2019-02-30 --out b.h5",
                                     dir, units_dir_env(dir));
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --start-time: 2019-02-30 is not a day of the calendar (see "
        "doorbench import --help)\n");
  dir.write("r.csv", "time_s,force_N,angle_rad\n0,1,0\n0.001,2,0\n");
  run = testing::run_doorbench_shell("import r.csv --rate-hz 100 --out b.h5", dir,
                                     units_dir_env(dir));
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --rate-hz is for TDMS files (*.tdms): a CSV's time_s gives the "
        "time (see doorbench import --help)\n");
  CHECK(!std::filesystem::exists(dir / "b.h5"));
}

TEST_CASE("Import: a control character in a CSV's metadata is refused where it is", "[csv][cli]") {
  const testing::TempDir dir("import_nul");
  dir.write("nul.csv", std::string("# operator: Ann") + '\0' +
                           "Bob\ntime_s,force_N,angle_rad\n0,1,0\n0.001,2,0\n");
  const testing::DoorbenchRun run =
      testing::run_doorbench_shell("import nul.csv --out n.h5", dir, units_dir_env(dir));
  CHECK(run.status == 1);
  CHECK(run.err ==
        "doorbench: nul.csv:1: control character \\x00 at column 16 of a metadata "
        "line (metadata is kept as text: remove it from the file)\n");
  CHECK(!std::filesystem::exists(dir / "n.h5"));
}

}  // namespace doorbench
