// Big-endian TDMS files (acquisition/session/tdms.h, docs/tdms.md "Byte order"): the same
// file written in both byte orders (tests/support/tdms_writer.h: the ToC little-endian, all
// after it big-endian when kTocBigEndian is set) reads back the same, value for value and
// property for property, through appended metadata, a Linear scale, a time stamp, integers
// of three widths and DAQmx raw data; `doorbench import` makes the same session of both.
// Also the byte offsets errors name (the field's first byte) and the Git LFS pointer.
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

constexpr std::uint32_t kI16 = 2;
constexpr int kOrderSamples = 40;  // 20 in each segment

double order_force(int k) {
  return 25.0 * std::sin(0.13 * k) - 1e-7 * k;
}
std::int32_t order_counts(int k) {
  return static_cast<std::int32_t>(std::lround(70000.0 * std::cos(0.04 * k))) - 123456;
}
float order_incl(int k) {
  return static_cast<float>(-2.25 * std::sin(0.07 * k));
}
std::int16_t order_pot(int k) {
  return static_cast<std::int16_t>(-32000 + 2100 * k);
}

Object order_channel(const std::string& name, std::uint32_t type, std::uint64_t count,
                     std::vector<Property> properties) {
  Object object;
  object.raw = Object::kNew;
  object.path = "/'Door'/'" + name + "'";
  object.type = type;
  object.count = count;
  object.properties = std::move(properties);
  return object;
}

Bytes order_raw(int from, int n, bool big) {
  Bytes raw;
  raw.big_endian = big;
  for (int k = from; k < from + n; ++k) raw.put(order_force(k));
  for (int k = from; k < from + n; ++k) raw.put(order_counts(k));
  for (int k = from; k < from + n; ++k) raw.put(order_incl(k));
  for (int k = from; k < from + n; ++k) raw.put(order_pot(k));
  return raw;
}

// Two segments: a new object list with the file's and a group's properties; then metadata
// appended (Force's index repeated, Angle's given anew) and more raw data.
std::vector<std::uint8_t> ordered_file(bool big) {
  const std::uint32_t order = big ? kTocBigEndian : 0;
  Object file_object;
  file_object.path = "/";
  file_object.properties = {double_property("handle_radius_m", 0.61, big),
                            text_property("operator", "Ann", big)};
  Object group;
  group.path = "/'Door'";
  group.properties = {i32_property("run", -7, big)};
  const std::vector<Object> first = {
      file_object,
      group,
      order_channel(
          "Force", kDouble, 20,
          {text_property("unit_string", "N", big), double_property("wf_increment", 0.001, big),
           time_property("wf_start_time", 3786912000, 1ull << 62, big)}),
      order_channel("Angle", kI32, 20,
                    {text_property("unit_string", "rad", big),
                     text_property("NI_Scaling_Status", "unscaled", big),
                     i32_property("NI_Number_Of_Scales", 1, big),
                     text_property("NI_Scale[0]_Scale_Type", "Linear", big),
                     double_property("NI_Scale[0]_Linear_Slope", 2.5e-6, big),
                     double_property("NI_Scale[0]_Linear_Y_Intercept", 0.25, big)}),
      order_channel("Incl", kSingle, 20, {text_property("unit_string", "deg", big)}),
      order_channel("Pot", kI16, 20, {})};
  Bytes file =
      segment(order | kTocMetaData | kTocNewObjList | kTocRawData, first, order_raw(0, 20, big));
  Object force_same;
  force_same.raw = Object::kSame;
  force_same.path = "/'Door'/'Force'";
  // Appended: Force and Angle keep their places, Incl and Pot are carried over unmentioned.
  const std::vector<Object> second = {
      force_same, order_channel("Angle", kI32, 20, {text_property("note", "second", big)})};
  file.append(segment(order | kTocMetaData | kTocRawData, second, order_raw(20, 20, big)));
  return file.data;
}

// DAQmx raw data: one raw buffer of 6 bytes (an I16 scaler at 0, an I32 at 2), a Linear scale.
std::vector<std::uint8_t> ordered_daqmx_file(bool big) {
  const std::uint32_t toc = (big ? kTocBigEndian : 0) | kTocMetaData | kTocNewObjList |
                            kTocRawData | kTocInterleavedData | kTocDAQmxRawData;
  const std::vector<Property> scales = {
      text_property("unit_string", "V", big),
      double_property("wf_increment", 0.0005, big),
      text_property("NI_Scaling_Status", "unscaled", big),
      i32_property("NI_Number_Of_Scales", 2, big),
      text_property("NI_Scale[1]_Scale_Type", "Linear", big),
      double_property("NI_Scale[1]_Linear_Slope", 3.0517578125e-4, big),
      double_property("NI_Scale[1]_Linear_Y_Intercept", -0.002, big),
      i32_property("NI_Scale[1]_Linear_Input_Source", 0, big)};
  const std::vector<Object> objects = {
      daqmx_channel("/'Dev1'/'Bridge'", 8, {{3, 0, 0, 0}}, {6}, false, scales, big),
      daqmx_channel("/'Dev1'/'Counter'", 8, {{5, 0, 2, 0}}, {6}, false, {}, big)};
  Bytes raw;
  raw.big_endian = big;
  for (int k = 0; k < 8; ++k) {
    raw.put(order_pot(k));
    raw.put(order_counts(k));
  }
  return segment(toc, objects, raw).data;
}

void check_same(const TdmsFile& big, const TdmsFile& little) {
  CHECK(big.segments == little.segments);
  REQUIRE(big.channels.size() == little.channels.size());
  for (std::size_t c = 0; c < little.channels.size(); ++c) {
    const TdmsChannel& b = big.channels[c];
    const TdmsChannel& l = little.channels[c];
    INFO(l.group << "/" << l.name);
    CHECK(b.group == l.group);
    CHECK(b.name == l.name);
    CHECK(b.data_type == l.data_type);
    CHECK(b.values == l.values);  // exact, value for value
    CHECK(b.scaling == l.scaling);
    CHECK(b.daqmx_raw == l.daqmx_raw);
    REQUIRE(b.properties.size() == l.properties.size());
    for (const auto& [name, property] : l.properties) {
      INFO(name);
      CHECK(b.properties.at(name).text == property.text);
      CHECK(b.properties.at(name).number == property.number);
    }
  }
  CHECK(big.group_properties.at("Door").at("run").number ==
        little.group_properties.at("Door").at("run").number);
  CHECK(big.file_properties.at("operator").text == little.file_properties.at("operator").text);
}

// Runs doorbench in `dir`, so that names in its messages are as given.
std::string order_dir_env(const testing::TempDir& dir) {
  return "env -C '" + dir.path.string() + "'";
}

}  // namespace

TEST_CASE("TDMS byte order: a big-endian file reads as its little-endian twin", "[tdms]") {
  const std::vector<std::uint8_t> big_bytes = ordered_file(true);
  const std::vector<std::uint8_t> little_bytes = ordered_file(false);
  REQUIRE(big_bytes.size() == little_bytes.size());
  REQUIRE(big_bytes != little_bytes);
  CHECK(big_bytes[4] == (kTocBigEndian | kTocMetaData | kTocNewObjList | kTocRawData));
  const TdmsFile big = parse_tdms(big_bytes, "big.tdms");
  const TdmsFile little = parse_tdms(little_bytes, "little.tdms");
  check_same(big, little);
  // And both hold what was written.
  const TdmsChannel* force = little.find("Door", "Force");
  const TdmsChannel* angle = big.find("Door", "Angle");
  const TdmsChannel* pot = big.find("Door", "Pot");
  REQUIRE(force);
  REQUIRE(angle);
  REQUIRE(pot);
  REQUIRE(force->values.size() == kOrderSamples);
  REQUIRE(pot->values.size() == kOrderSamples);
  for (int k = 0; k < kOrderSamples; ++k) {
    CHECK(force->values[k] == order_force(k));
    CHECK(angle->values[k] == 2.5e-6 * order_counts(k) + 0.25);
    CHECK(pot->values[k] == order_pot(k));
  }
  CHECK(big.find("Door", "Force")->properties.at("wf_start_time").text ==
        "2024-01-01T00:00:00.250000Z");

  const TdmsFile big_daqmx = parse_tdms(ordered_daqmx_file(true), "big-daqmx.tdms");
  const TdmsFile little_daqmx = parse_tdms(ordered_daqmx_file(false), "little-daqmx.tdms");
  REQUIRE(little_daqmx.channels.size() == 2);
  CHECK(big_daqmx.channels[0].values == little_daqmx.channels[0].values);
  CHECK(big_daqmx.channels[0].daqmx_raw == little_daqmx.channels[0].daqmx_raw);
  CHECK(big_daqmx.channels[1].values == little_daqmx.channels[1].values);
  CHECK(little_daqmx.channels[1].values.at(3) == order_counts(3));
  CHECK(big_daqmx.channels[0].values.at(3) == 3.0517578125e-4 * order_pot(3) - 0.002);
}

TEST_CASE("TDMS byte order: doorbench import makes the same session of both", "[tdms][cli]") {
  const testing::TempDir dir("tdms_byte_order");
  std::vector<Recording> recordings;
  for (const bool big : {false, true}) {
    const std::vector<std::uint8_t> bytes = ordered_file(big);
    const std::string name = big ? "big" : "little";
    std::ofstream(dir / (name + ".tdms"), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    const testing::DoorbenchRun run = testing::run_doorbench_shell(
        "import " + name + ".tdms --map force=Door/Force,angle=Door/Angle,incl_deg=Door/Incl " +
            "--out " + name + ".h5",
        dir, order_dir_env(dir));
    INFO(run.err);
    REQUIRE(run.status == 0);
    recordings.push_back(session_to_recording(SessionReader(dir / (name + ".h5"))));
  }
  CHECK(recordings[1].force_N == recordings[0].force_N);
  CHECK(recordings[1].time_s == recordings[0].time_s);
  REQUIRE(recordings[0].angle_rad);
  REQUIRE(recordings[1].angle_rad);
  CHECK(*recordings[1].angle_rad == *recordings[0].angle_rad);
  CHECK(recordings[1].extra_columns == recordings[0].extra_columns);
  CHECK(recordings[1].handle_radius_m == 0.61);
  CHECK(SessionReader(dir / "big.h5").metadata().start_time_utc == "2024-01-01T00:00:00.250000Z");
}

TEST_CASE("TDMS: messages name the byte where the field at fault starts", "[tdms]") {
  const std::uint32_t toc = kTocMetaData | kTocNewObjList | kTocRawData;
  const std::vector<std::uint8_t> good = ordered_file(false);
  // The version is bytes 8-11, the next segment's offset 12-19, the raw data's 20-27.
  std::vector<std::uint8_t> version = good;
  version[8] = 0x67;  // 4711
  CHECK(error_of(version) ==
        "mem.tdms: segment 1 (byte 8): TDMS version 4711 is not supported (4712 and 4713 are)");
  std::vector<std::uint8_t> big_version = ordered_file(true);
  big_version[11] = 0x67;
  CHECK(error_of(big_version) ==
        "mem.tdms: segment 1 (byte 8): TDMS version 4711 is not supported (4712 and 4713 are) "
        "(read big-endian: the ToC says so)");
  std::vector<std::uint8_t> cut = segment(toc, {}, Bytes{}).data;
  cut[12] = 0xFF;
  CHECK(error_of(cut) ==
        "mem.tdms: segment 1 (byte 12): the next segment offset (255) points past the end of "
        "the file (32 bytes)");
  std::vector<std::uint8_t> raw_offset = segment(toc, {}, Bytes{}).data;
  raw_offset[20] = 9;
  CHECK(error_of(raw_offset) ==
        "mem.tdms: segment 1 (byte 20): the raw data offset (9) points past the segment's end");
  // A property of a type that is not supported: its type code at byte 32 + 4 + 1 + 4 + 4 + 4 + 1.
  Object file_object;
  file_object.path = "/";
  file_object.properties = {{"p", 0x4F, Bytes{}}};  // fixed point
  CHECK(error_of(segment(kTocMetaData | kTocNewObjList, {file_object}, Bytes{}).data) ==
        "mem.tdms: segment 1 (byte 50): properties of type fixed point are not supported");
  std::vector<std::uint8_t> path =
      segment(kTocMetaData | kTocNewObjList, {file_object}, Bytes{}).data;
  path[36] = 'x';  // the path "/" at byte 36 (its length at 32)
  CHECK(error_of(path) ==
        "mem.tdms: segment 1 (byte 32): object path 'x' is not of the form /'group'/'channel'");
  std::vector<std::uint8_t> junk = good;
  junk[0] = 'P';
  junk[1] = 'K';
  CHECK(error_of(junk) ==
        "mem.tdms: segment 1 (byte 0): no TDMS segment here (a segment starts with 'TDSm'; "
        "these bytes are 'PKSm')");
}

TEST_CASE("TDMS: a Git LFS pointer in place of the file is named as such", "[tdms][cli]") {
  const std::string pointer =
      "version https://git-lfs.github.com/spec/v1\n"
      "oid sha256:4d7a214614ab2935c943f9e0ff69d22eadbb8f32b1258daaa5e2ca24d17e2393\n"
      "size 57171\n";
  const std::vector<std::uint8_t> bytes(pointer.begin(), pointer.end());
  CHECK(error_of(bytes) ==
        "mem.tdms: this is a Git LFS pointer to a file of 57171 bytes (oid sha256:4d7a2146...), "
        "not the file itself: fetch it (git lfs pull) and import that");
  const testing::TempDir dir("tdms_lfs");
  dir.write("run.tdms", pointer);
  dir.write("run.csv", pointer);
  const testing::DoorbenchRun tdms = testing::run_doorbench_shell(
      "import run.tdms --map force=A/B,angle=A/C --out s.h5", dir, order_dir_env(dir));
  CHECK(tdms.status == 1);
  CHECK(tdms.err ==
        "doorbench: run.tdms: this is a Git LFS pointer to a file of 57171 bytes (oid "
        "sha256:4d7a2146...), not the file itself: fetch it (git lfs pull) and import that\n");
  const testing::DoorbenchRun csv =
      testing::run_doorbench_shell("import run.csv --out s.h5", dir, order_dir_env(dir));
  CHECK(csv.status == 1);
  CHECK(csv.err ==
        "doorbench: run.csv: this is a Git LFS pointer to a file of 57171 bytes (oid "
        "sha256:4d7a2146...), not the file itself: fetch it (git lfs pull) and import that\n");
}

}  // namespace doorbench
