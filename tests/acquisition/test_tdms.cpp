// TDMS import (acquisition/session/tdms.h, docs/tdms.md): files written by a writer of NI's
// published layout (tests/support/tdms_writer.h) are read back bit for bit, through segments with
// new and appended object lists, repeated raw data indexes, chunks, interleaved data, a
// skipped string channel and a Linear scale; `doorbench import` makes a session of them;
// the layouts that are not supported are refused by name.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "acquisition/session/session_csv.h"
#include "acquisition/session/session_file.h"
#include "acquisition/session/tdms.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/tdms_error.h"
#include "tests/support/tdms_writer.h"

namespace doorbench {
namespace {

using namespace testing::tdms;
using Catch::Matchers::Contains;

constexpr int kSamples = 115;  // 2 chunks of 25, 25, 20 interleaved, 20 interleaved

double force_at(int k) {
  return 10.0 * std::sin(0.1 * k) + 0.123456789 * k;
}
std::int32_t counts_at(int k) {
  return static_cast<std::int32_t>(std::lround(500.0 * (1.0 - std::cos(0.05 * k))));
}
float incl_at(int k) {
  return static_cast<float>(3.7 * std::sin(0.05 * k));
}

struct Expected {
  std::vector<double> force, angle, incl;
};
Expected expected() {
  Expected e;
  for (int k = 0; k < kSamples; ++k) {
    e.force.push_back(force_at(k));
    e.angle.push_back(0.001 * static_cast<double>(counts_at(k)) + 0.0);  // the Linear scale
    e.incl.push_back(static_cast<double>(incl_at(k)));
  }
  return e;
}

// Samples [from, from + n) of the three channels, non-interleaved (with the string
// channel's 8 bytes when `with_note`), or interleaved.
Bytes raw_block(int from, int n, bool interleaved, bool with_note) {
  Bytes raw;
  if (interleaved) {
    for (int k = from; k < from + n; ++k) {
      raw.put(force_at(k));
      raw.put(counts_at(k));
      raw.put(incl_at(k));
    }
    return raw;
  }
  for (int k = from; k < from + n; ++k) raw.put(force_at(k));
  for (int k = from; k < from + n; ++k) raw.put(counts_at(k));
  for (int k = from; k < from + n; ++k) raw.put(incl_at(k));
  if (with_note) {
    raw.put<std::uint32_t>(4);  // the string's end offset, then its text
    raw.data.insert(raw.data.end(), {'o', 'p', 'e', 'n'});
  }
  return raw;
}

Object channel(const std::string& name, std::uint32_t type, std::uint64_t count,
               std::vector<Property> properties = {}) {
  Object object;
  object.raw = Object::kNew;
  object.path = "/'Door'/'" + name + "'";
  object.type = type;
  object.count = count;
  object.properties = std::move(properties);
  return object;
}

// Four segments: (1) a new object list, non-interleaved, two chunks, a string channel;
// (2) appended metadata: Force's index repeated, Angle's given anew with a new property,
// Incl and Note carried over unmentioned; (3) a new object list, interleaved; (4) raw data
// only, interleaved, the object list of (3).
std::vector<std::uint8_t> door_file() {
  Object file_object;
  file_object.path = "/";
  file_object.properties = {double_property("handle_radius_m", 0.8),
                            text_property("name", "bench B")};
  Object group;
  group.path = "/'Door'";
  Object note;
  note.raw = Object::kNew;
  note.path = "/'Door'/'Note'";
  note.type = kString;
  note.count = 1;
  note.string_bytes = 8;
  const std::vector<Object> first = {
      file_object,
      group,
      channel("Force", kDouble, 25,
              {text_property("unit_string", "N"), double_property("wf_increment", 0.02),
               double_property("wf_start_offset", 0.0),
               time_property("wf_start_time", 3786912000, 1ull << 63)}),
      channel(
          "Angle", kI32, 25,
          {text_property("unit_string", "rad"), double_property("wf_increment", 0.02),
           text_property("NI_Scaling_Status", "unscaled"), i32_property("NI_Number_Of_Scales", 1),
           text_property("NI_Scale[0]_Scale_Type", "Linear"),
           double_property("NI_Scale[0]_Linear_Slope", 0.001),
           double_property("NI_Scale[0]_Linear_Y_Intercept", 0.0),
           i32_property("NI_Scale[0]_Linear_Input_Source", -1)}),
      channel("Incl", kSingle, 25, {text_property("unit_string", "deg")}),
      note};
  Bytes raw1 = raw_block(0, 25, false, true);
  raw1.append(raw_block(25, 25, false, true));
  Bytes file = segment(kTocMetaData | kTocNewObjList | kTocRawData, first, raw1);

  Object force_same;
  force_same.raw = Object::kSame;
  force_same.path = "/'Door'/'Force'";
  const std::vector<Object> second = {
      force_same, channel("Angle", kI32, 25, {text_property("comment", "appended")})};
  file.append(segment(kTocMetaData | kTocRawData, second, raw_block(50, 25, false, true)));

  const std::vector<Object> third = {channel("Force", kDouble, 20), channel("Angle", kI32, 20),
                                     channel("Incl", kSingle, 20)};
  file.append(segment(kTocMetaData | kTocNewObjList | kTocRawData | kTocInterleavedData, third,
                      raw_block(75, 20, true, false)));
  file.append(segment(kTocRawData | kTocInterleavedData, {}, raw_block(95, 20, true, false)));
  return file.data;
}

}  // namespace

TEST_CASE("TDMS: segments, chunks, interleaving and scaling read back bit for bit", "[tdms]") {
  const TdmsFile file = parse_tdms(door_file(), "door.tdms");
  CHECK(file.segments == 4);
  const Expected e = expected();
  const TdmsChannel* force = file.find("Door", "Force");
  const TdmsChannel* angle = file.find("Door", "Angle");
  const TdmsChannel* incl = file.find("Door", "Incl");
  REQUIRE(force);
  REQUIRE(angle);
  REQUIRE(incl);
  CHECK(force->data_type == "DBL");
  CHECK(angle->data_type == "I32");
  CHECK(incl->data_type == "SGL");
  CHECK(force->values == e.force);  // exact equality, element by element
  CHECK(angle->values == e.angle);
  CHECK(incl->values == e.incl);
  CHECK(angle->scaling == "NI_Scale[0] (Linear)");
  CHECK(angle->properties.at("comment").text == "appended");
  CHECK(force->properties.at("wf_start_time").text == "2024-01-01T00:00:00.500000Z");
  CHECK(file.find("Door", "Note")->values.empty());  // the string channel is skipped
  CHECK(file.file_properties.at("name").text == "bench B");

  const Recording recording = tdms_to_recording(
      file, parse_tdms_map("force=Door/Force,angle=Door/Angle,inclinometer_angle_deg=Door/Incl"),
      "door.tdms");
  REQUIRE(recording.size() == kSamples);
  for (int i = 0; i < kSamples; ++i) CHECK(recording.time_s[i] == 0.0 + i * 0.02);
  CHECK(recording.force_N == e.force);
  CHECK(*recording.angle_rad == e.angle);
  REQUIRE(recording.extra_names == std::vector<std::string>{"inclinometer_angle_deg"});
  CHECK(recording.extra_columns[0] == e.incl);
  CHECK(recording.handle_radius_m == 0.8);
}

TEST_CASE("TDMS: doorbench import makes a session with the samples bit for bit", "[tdms][cli]") {
  const testing::TempDir dir("tdms_import");
  const std::vector<std::uint8_t> bytes = door_file();
  std::ofstream(dir / "door.tdms", std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  const std::string tdms = (dir / "door.tdms").string();
  testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import '" + tdms +
          "' --map force=Door/Force,angle=Door/Angle,inclinometer_angle_deg=Door/Incl --out '" +
          (dir / "s.h5").string() + "'",
      dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const SessionReader session(dir / "s.h5");
  const Recording recording = session_to_recording(session);
  const Expected e = expected();
  CHECK(recording.force_N == e.force);
  REQUIRE(recording.angle_rad);
  CHECK(*recording.angle_rad == e.angle);
  REQUIRE(recording.extra_names == std::vector<std::string>{"inclinometer_angle_deg"});
  CHECK(recording.extra_columns[0] == e.incl);
  REQUIRE(recording.size() == kSamples);
  for (int i = 0; i < kSamples; ++i) CHECK(recording.time_s[i] == 0.0 + i * 0.02);
  CHECK(recording.handle_radius_m == 0.8);

  run = testing::run_doorbench_shell("import '" + tdms +
                                         "' --map force=Door/Force,angle=Door/Nope --out '" +
                                         (dir / "t.h5").string() + "'",
                                     dir);
  CHECK(run.status == 1);
  const std::string channels =
      "; the file's channels: Door/Force, Door/Angle, Door/Incl, "
      "Door/Note\n";
  CHECK(run.err == "doorbench: " + tdms + ": angle: no channel Door/Nope" + channels);
  run = testing::run_doorbench_shell(
      "import '" + tdms + "' --map force --out '" + (dir / "t.h5").string() + "'", dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: --map item 'force' is not TARGET=GROUP/CHANNEL (e.g. force=Load/Force); the "
        "file's channels: Door/Force, Door/Angle, Door/Incl, Door/Note (see doorbench import "
        "--help)\n");
  // A channel in degrees as the angle is converted exactly (record unit-angle); one in
  // radians as the force is refused.
  run = testing::run_doorbench_shell("import '" + tdms +
                                         "' --map force=Door/Force,angle=Door/Incl --out '" +
                                         (dir / "deg.h5").string() + "'",
                                     dir);
  CHECK(run.status == 0);
  CHECK(SessionReader(dir / "deg.h5").channel("angle").calibration_id == "unit-angle");
  run = testing::run_doorbench_shell("import '" + tdms +
                                         "' --map force=Door/Angle,angle=Door/Incl --out '" +
                                         (dir / "t.h5").string() + "'",
                                     dir);
  CHECK(run.status == 1);
  CHECK(run.err == "doorbench: " + tdms +
                       ": force: channel Door/Angle is in 'rad', not N (convert it: "
                       "--calibration force=RECORD or --scale force=GAIN[,OFFSET]; or map it as "
                       "an extra column whose name ends in its unit)" +
                       channels);

  // Without --map: the channels to map.
  run = testing::run_doorbench_shell(
      "import '" + tdms + "' --out '" + (dir / "t.h5").string() + "'", dir);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "doorbench: a TDMS file needs --map force=GROUP/CHANNEL,angle=GROUP/CHANNEL (or rate=); "
        "the file's channels: Door/Force, Door/Angle, Door/Incl, Door/Note (see doorbench "
        "import --help)\n");
  // One channel as two targets.
  run = testing::run_doorbench_shell("import '" + tdms +
                                         "' --map force=Door/Force,angle=Door/Force --out '" +
                                         (dir / "t.h5").string() + "'",
                                     dir);
  CHECK(run.status == 1);
  CHECK(run.err == "doorbench: " + tdms +
                       ": angle: channel Door/Force is mapped as force already (one channel per "
                       "target)" +
                       channels);
  CHECK_FALSE(std::filesystem::exists(dir / "t.h5"));
  // The index file beside a .tdms.
  std::ofstream(dir / "door.tdms_index") << "TDSh";
  const std::string index = (dir / "door.tdms_index").string();
  run = testing::run_doorbench_shell("import '" + index +
                                         "' --map force=Door/Force,angle=Door/Angle --out '" +
                                         (dir / "t.h5").string() + "'",
                                     dir);
  CHECK(run.status == 1);
  CHECK(run.err == "doorbench: " + index +
                       ": this is a TDMS index file (.tdms_index); import the .tdms file itself (" +
                       tdms + ")\n");
  // The file's wf_start_time (3786912000.5 s after 1904) is the session's start.
  run = testing::run_doorbench_shell("info '" + (dir / "s.h5").string() + "'", dir);
  INFO(run.out);
  CHECK_THAT(run.out, Contains("2024-01-01T00:00:00.500000Z"));
  CHECK(SessionReader(dir / "s.h5").metadata().start_time_utc == "2024-01-01T00:00:00.500000Z");
}

// A SignalExpress-style group named with a date ('/' in it) and a channel with a comma.
TEST_CASE(
    "TDMS: --map takes names with '/' and ',' (escaped, or '/' unescaped when only one "
    "split names a channel)",
    "[tdms][cli]") {
  const testing::TempDir dir("tdms_names");
  const std::string group = "07/09/2012 06:58:23 PM - Digital Input - All Data";
  Object force = channel("Force", kDouble, 4, {double_property("wf_increment", 0.5)});
  force.path = "/'" + group + "'/'Force'";
  Object angle = channel("Angle, rad", kDouble, 4);
  angle.path = "/'" + group + "'/'Angle, rad'";
  Bytes raw;
  for (double v : {1.0, 2.0, 3.0, 4.0}) raw.put(v);
  for (double v : {0.1, 0.2, 0.3, 0.4}) raw.put(v);
  const Bytes file = segment(kTocMetaData | kTocNewObjList | kTocRawData, {force, angle}, raw);
  std::ofstream(dir / "se.tdms", std::ios::binary)
      .write(reinterpret_cast<const char*>(file.data.data()),
             static_cast<std::streamsize>(file.data.size()));
  const std::string tdms = (dir / "se.tdms").string();
  const std::string escaped_group = "07\\/09\\/2012 06:58:23 PM - Digital Input - All Data";
  // Escaped: any name; unescaped '/': the one split that names a channel.
  for (const std::string& map :
       {"force=" + escaped_group + "/Force,angle=" + escaped_group + "/Angle\\, rad",
        "force=" + group + "/Force,angle=" + group + "/Angle\\, rad"}) {
    INFO(map);
    std::filesystem::remove(dir / "s.h5");
    const testing::DoorbenchRun run = testing::run_doorbench_shell(
        "import '" + tdms + "' --map '" + map + "' --out '" + (dir / "s.h5").string() + "'", dir);
    INFO(run.err);
    REQUIRE(run.status == 0);
    const Recording recording = session_to_recording(SessionReader(dir / "s.h5"));
    CHECK(recording.force_N == std::vector<double>{1, 2, 3, 4});
    REQUIRE(recording.angle_rad);
    CHECK(*recording.angle_rad == std::vector<double>{0.1, 0.2, 0.3, 0.4});
  }
  const std::vector<TdmsMapItem> items = parse_tdms_map("force=a\\/b/c\\,d\\\\,x_V=e/f");
  REQUIRE(items.size() == 2);
  CHECK(items[0].group == "a/b");
  CHECK(items[0].channel == "c,d\\");
  CHECK(items[1].target == "x_V");
  // A name the error lists is a name --map takes.
  const testing::DoorbenchRun wrong = testing::run_doorbench_shell(
      "import '" + tdms + "' --map force=Nope/Force,angle=Nope/Angle --out '" +
          (dir / "t.h5").string() + "'",
      dir);
  CHECK(wrong.status == 1);
  CHECK(wrong.err == "doorbench: " + tdms +
                         ": force: no channel Nope/Force; the file's channels: " + escaped_group +
                         "/Force, " + escaped_group + "/Angle\\, rad\n");
}

TEST_CASE("TDMS: layouts that are not supported are refused by name", "[tdms]") {
  const Bytes raw = raw_block(0, 5, false, false);
  const std::vector<Object> objects = {channel("Force", kDouble, 5), channel("Angle", kI32, 5),
                                       channel("Incl", kSingle, 5)};
  const std::uint32_t toc = kTocMetaData | kTocNewObjList | kTocRawData;
  // The DAQmx flag alone changes nothing (tests/acquisition/test_tdms_daqmx.cpp reads DAQmx
  // raw data).
  CHECK(error_of(segment(toc | kTocDAQmxRawData, objects, raw).data) == "(no error)");
  // Big-endian segments are read (tests/acquisition/test_tdms_byte_order.cpp).
  CHECK(error_of(segment(toc, objects, raw, 4711).data) ==
        "mem.tdms: segment 1 (byte 8): TDMS version 4711 is not supported (4712 and 4713 are)");

  std::vector<Object> daqmx = objects;
  daqmx[0] = daqmx_channel("/'Door'/'Force'", 5, {{0xFFFFFFFFu, 0, 0, 0}}, {8}, false);
  // Byte 51: the object's raw data index (after the lead-in, the object count and the path).
  CHECK(error_of(segment(toc, daqmx, raw).data) ==
        "mem.tdms: segment 1 (byte 51): object /'Door'/'Force': DAQmx scalers of data type "
        "4294967295 are not supported (0-9: U8, I8, U16, I16, U32, I32, U64, I64, SGL, DBL are)");
  std::vector<Object> extended = objects;
  extended[0].type = kExtended;
  CHECK(error_of(segment(toc, extended, raw).data) ==
        "mem.tdms: segment 1 (byte 51): object /'Door'/'Force': channels of type EXT (extended "
        "float) are not supported (I8-I64, U8-U64, SGL, DBL are; strings are skipped)");
  Bytes short_raw = raw;
  short_raw.data.pop_back();
  // Byte 160: where the raw data start.
  CHECK(error_of(segment(toc, objects, short_raw).data) ==
        "mem.tdms: segment 1 (byte 160): raw data of 79 bytes is not a whole number of 80-byte "
        "chunks (partial chunks are not supported)");
  std::vector<Object> thermocouple = objects;
  thermocouple[1].properties = {text_property("NI_Scaling_Status", "unscaled"),
                                i32_property("NI_Number_Of_Scales", 1),
                                text_property("NI_Scale[0]_Scale_Type", "Thermocouple")};
  CHECK(error_of(segment(toc, thermocouple, raw).data) ==
        "mem.tdms: channel Door/Angle: NI_Scale[0]_Scale_Type 'Thermocouple' is not supported "
        "(Linear and Polynomial are)");
  std::vector<std::uint8_t> index_file = segment(toc, objects, raw).data;
  index_file[3] = 'h';
  CHECK(error_of(index_file) ==
        "mem.tdms: segment 1 (byte 0): this is a TDMS index file (.tdms_index); import the "
        ".tdms file itself");
  std::vector<std::uint8_t> cut = segment(toc, objects, raw).data;
  cut.resize(cut.size() - 10);
  CHECK(error_of(cut) == "mem.tdms: segment 1 (byte 12): the next segment offset (" +
                             std::to_string(cut.size() + 10 - 28) +
                             ") points past the end of the file (" + std::to_string(cut.size()) +
                             " bytes)");
}

}  // namespace doorbench

namespace doorbench {

TEST_CASE("TDMS: a Polynomial scale fed by a Linear one", "[tdms]") {
  using namespace testing::tdms;
  const std::vector<std::int32_t> raw_counts = {-7, 0, 3, 1000, 65535};
  Object pot;
  pot.raw = Object::kNew;
  pot.path = "/'Bench'/'Pot'";
  pot.type = kI32;
  pot.count = raw_counts.size();
  pot.properties = {text_property("NI_Scaling_Status", "unscaled"),
                    i32_property("NI_Number_Of_Scales", 2),
                    text_property("NI_Scale[0]_Scale_Type", "Linear"),
                    double_property("NI_Scale[0]_Linear_Slope", 0.5),
                    double_property("NI_Scale[0]_Linear_Y_Intercept", 1.0),
                    text_property("NI_Scale[1]_Scale_Type", "Polynomial"),
                    i32_property("NI_Scale[1]_Polynomial_Coefficients_Size", 3),
                    double_property("NI_Scale[1]_Polynomial_Coefficients[0]", 0.5),
                    double_property("NI_Scale[1]_Polynomial_Coefficients[1]", 2.0),
                    double_property("NI_Scale[1]_Polynomial_Coefficients[2]", 0.25),
                    i32_property("NI_Scale[1]_Polynomial_Input_Source", 0)};
  Bytes raw;
  for (std::int32_t count : raw_counts) raw.put(count);
  const TdmsFile file =
      parse_tdms(segment(kTocMetaData | kTocNewObjList | kTocRawData, {pot}, raw).data, "p.tdms");
  const TdmsChannel* channel = file.find("Bench", "Pot");
  REQUIRE(channel);
  CHECK(channel->scaling == "NI_Scale[1] (Polynomial)");
  REQUIRE(channel->values.size() == raw_counts.size());
  for (std::size_t i = 0; i < raw_counts.size(); ++i) {
    const double x = 0.5 * raw_counts[i] + 1.0;
    CHECK(channel->values[i] == (0.25 * x + 2.0) * x + 0.5);
  }
}

}  // namespace doorbench
