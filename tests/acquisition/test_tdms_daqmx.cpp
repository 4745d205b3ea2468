// DAQmx raw data in TDMS files (acquisition/tdms.h, docs/tdms.md "DAQmx raw data"): files
// written in the layout DAQmx logging uses (tests/support/tdms_writer.h daqmx_channel: the
// 0x69120000 / 0x69130000 raw data indexes with their scalers and raw buffer widths, each
// raw buffer's samples as strides holding every scaler's value) read back as the values
// their NI_Scale properties give; digital lines as 0/1; what is not read is refused by name.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "acquisition/session/session_csv.h"
#include "acquisition/session/session_file.h"
#include "acquisition/session/tdms.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/tdms_writer.h"

namespace doorbench {
namespace {

using namespace testing::tdms;

constexpr std::uint32_t kDaqmxToc =  // 0xAE: as DAQmx logging writes it
    kTocMetaData | kTocNewObjList | kTocRawData | kTocInterleavedData | kTocDAQmxRawData;
constexpr int kChunk = 40;

std::int16_t force_counts(int k) {
  return static_cast<std::int16_t>(std::lround(12000.0 * std::sin(0.07 * k) - 300.0));
}
std::int32_t angle_counts(int k) {
  return static_cast<std::int32_t>(std::lround(90000.0 * (1.0 - std::cos(0.03 * k))));
}
float incl_volts(int k) {
  return static_cast<float>(2.5 * std::sin(0.05 * k));
}
std::uint8_t lines(int k) {
  return static_cast<std::uint8_t>((k / 3) % 4);  // line 0 and line 1 of port 0
}

// The scaled values as NI's reader gives them: Force a Linear scale of its I16 scaler;
// Angle a Polynomial of a Linear of its I32 scaler.
double force_N(int k) {
  return 0.0123456789 * force_counts(k) - 1.5;
}
double angle_rad(int k) {
  const double x = 2.5e-5 * angle_counts(k) + 0.01;
  return 0.002 + 0.98 * x + 0.0125 * x * x;
}

std::vector<Property> force_scales() {
  return {text_property("unit_string", "N"),
          double_property("wf_increment", 0.001),
          text_property("NI_Scaling_Status", "unscaled"),
          i32_property("NI_Number_Of_Scales", 2),
          double_property("NI_Scale[1]_Linear_Slope", 0.0123456789),
          double_property("NI_Scale[1]_Linear_Y_Intercept", -1.5),
          text_property("NI_Scale[1]_Scale_Type", "Linear"),
          i32_property("NI_Scale[1]_Linear_Input_Source", 0)};
}
std::vector<Property> angle_scales() {
  return {text_property("unit_string", "rad"),
          double_property("wf_increment", 0.001),
          text_property("NI_Scaling_Status", "unscaled"),
          i32_property("NI_Number_Of_Scales", 3),
          text_property("NI_Scale[1]_Scale_Type", "Linear"),
          double_property("NI_Scale[1]_Linear_Slope", 2.5e-5),
          double_property("NI_Scale[1]_Linear_Y_Intercept", 0.01),
          i32_property("NI_Scale[1]_Linear_Input_Source", 0),
          text_property("NI_Scale[2]_Scale_Type", "Polynomial"),
          i32_property("NI_Scale[2]_Polynomial_Coefficients_Size", 3),
          double_property("NI_Scale[2]_Polynomial_Coefficients[0]", 0.002),
          double_property("NI_Scale[2]_Polynomial_Coefficients[1]", 0.98),
          double_property("NI_Scale[2]_Polynomial_Coefficients[2]", 0.0125),
          i32_property("NI_Scale[2]_Polynomial_Input_Source", 1)};
}

// Two devices: raw buffer 0 (8 bytes a sample: Force's I16 at 0, 2 bytes unused, Angle's
// I32 at 4), raw buffer 1 (5 bytes: Incl's SGL at 0, the digital port's U8 at 4, lines 0
// and 1 at bits 32 and 33). Two chunks of kChunk samples in the first segment, one in the
// second (raw data only, the same object list).
std::vector<std::uint8_t> daqmx_file(bool with_digital) {
  const std::vector<std::uint32_t> widths = {8, 5};
  Object group;
  group.path = "/'Dev1'";
  std::vector<Object> objects = {
      group,
      daqmx_channel("/'Dev1'/'Force'", kChunk, {{3, 0, 0, 0}}, widths, false, force_scales()),
      daqmx_channel("/'Dev1'/'Angle'", kChunk, {{5, 0, 4, 0}}, widths, false, angle_scales()),
      daqmx_channel("/'Dev1'/'Incl'", kChunk, {{8, 1, 0, 0}}, widths, false,
                    {text_property("unit_string", "V")})};
  if (with_digital) {
    objects.push_back(
        daqmx_channel("/'Dev1'/'port0 line0'", kChunk, {{0, 1, 32, 0}}, widths, true));
    objects.push_back(
        daqmx_channel("/'Dev1'/'port0 line1'", kChunk, {{0, 1, 33, 0}}, widths, true));
  }
  auto chunk = [&](int from) {
    Bytes raw;
    for (int k = from; k < from + kChunk; ++k) {
      raw.put(force_counts(k));
      raw.put<std::uint16_t>(0xBEEF);
      raw.put(angle_counts(k));
    }
    for (int k = from; k < from + kChunk; ++k) {
      raw.put(incl_volts(k));
      raw.put(lines(k));
    }
    return raw;
  };
  Bytes raw = chunk(0);
  raw.append(chunk(kChunk));
  Bytes file = segment(kDaqmxToc, objects, raw);
  file.append(segment(kTocRawData | kTocInterleavedData | kTocDAQmxRawData, {}, chunk(2 * kChunk)));
  return file.data;
}

}  // namespace

TEST_CASE("TDMS DAQmx: raw data with Linear and Polynomial scales read as NI scales them",
          "[tdms][daqmx]") {
  const TdmsFile file = parse_tdms(daqmx_file(true), "daqmx.tdms");
  const TdmsChannel* force = file.find("Dev1", "Force");
  const TdmsChannel* angle = file.find("Dev1", "Angle");
  const TdmsChannel* incl = file.find("Dev1", "Incl");
  REQUIRE(force);
  REQUIRE(angle);
  REQUIRE(incl);
  CHECK(force->data_type == "DAQmx raw data");
  CHECK(force->scaling == "NI_Scale[1] (Linear)");
  CHECK(angle->scaling == "NI_Scale[2] (Polynomial)");
  CHECK(incl->scaling == "DAQmx scaler 0 (raw)");
  const int n = 3 * kChunk;
  REQUIRE(force->values.size() == n);
  REQUIRE(angle->values.size() == n);
  REQUIRE(incl->values.size() == n);
  REQUIRE(force->daqmx_raw.at(0).size() == n);
  for (int k = 0; k < n; ++k) {
    INFO("sample " << k);
    CHECK(force->values[k] == Approx(force_N(k)).epsilon(1e-12).margin(1e-15));
    CHECK(angle->values[k] == Approx(angle_rad(k)).epsilon(1e-12).margin(1e-15));
    CHECK(incl->values[k] == static_cast<double>(incl_volts(k)));
    CHECK(force->daqmx_raw.at(0)[k] == force_counts(k));  // the raw counts kept
  }
}

TEST_CASE("TDMS DAQmx: digital lines read as 0/1 and the file imports", "[tdms][daqmx][cli]") {
  const std::vector<std::uint8_t> bytes = daqmx_file(true);
  const TdmsFile file = parse_tdms(bytes, "daqmx.tdms");
  const TdmsChannel* line0 = file.find("Dev1", "port0 line0");
  const TdmsChannel* line1 = file.find("Dev1", "port0 line1");
  REQUIRE(line0);
  REQUIRE(line1);
  REQUIRE(line0->values.size() == 3 * kChunk);
  for (int k = 0; k < 3 * kChunk; ++k) {
    CHECK(line0->values[k] == (lines(k) & 1));
    CHECK(line1->values[k] == ((lines(k) >> 1) & 1));
  }
  const testing::TempDir dir("tdms_daqmx");
  const std::string tdms = (dir / "daqmx.tdms").string();
  std::ofstream(tdms, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  const testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import '" + tdms +
          "' --map 'force=Dev1/Force,angle=Dev1/Angle,incl_V=Dev1/Incl,latch_bool=Dev1/port0 "
          "line0' --out '" +
          (dir / "s.h5").string() + "'",
      dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const Recording recording = session_to_recording(SessionReader(dir / "s.h5"));
  REQUIRE(recording.size() == 3 * kChunk);
  REQUIRE(recording.angle_rad);
  REQUIRE(recording.extra_names == std::vector<std::string>{"incl_V", "latch_bool"});
  for (int k = 0; k < 3 * kChunk; ++k) {
    CHECK(recording.force_N[k] == Approx(force_N(k)).epsilon(1e-12).margin(1e-15));
    CHECK((*recording.angle_rad)[k] == Approx(angle_rad(k)).epsilon(1e-12).margin(1e-15));
    CHECK(recording.extra_columns[1][k] == (lines(k) & 1));
    CHECK(recording.time_s[k] == Approx(0.001 * k));
  }
}

TEST_CASE("TDMS DAQmx: what is not read is refused by name", "[tdms][daqmx]") {
  auto error_of = [](const std::vector<Object>& objects, const Bytes& raw) -> std::string {
    try {
      parse_tdms(segment(kDaqmxToc, objects, raw).data, "mem.tdms");
    } catch (const TdmsError& error) {
      return error.what();
    }
    return "(no error)";
  };
  Bytes raw;
  for (int k = 0; k < 4; ++k) raw.put<std::int32_t>(k);
  std::vector<Property> thermocouple = {text_property("NI_Scaling_Status", "unscaled"),
                                        i32_property("NI_Number_Of_Scales", 2),
                                        text_property("NI_Scale[1]_Scale_Type", "Thermocouple")};
  CHECK(
      error_of({daqmx_channel("/'Dev1'/'T'", 4, {{5, 0, 0, 0}}, {4}, false, thermocouple)}, raw) ==
      "mem.tdms: channel Dev1/T: NI_Scale[1]_Scale_Type 'Thermocouple' is not supported "
      "(Linear and Polynomial are)");
  // Byte 47: the raw data index, after the lead-in, the object count and the path.
  CHECK(error_of({daqmx_channel("/'Dev1'/'T'", 4, {{5, 0, 2, 0}}, {4}, false)}, raw) ==
        "mem.tdms: segment 1 (byte 47): object /'Dev1'/'T': DAQmx scaler 0 reads past its raw "
        "buffer's width");
  Object plain;
  plain.raw = Object::kNew;
  plain.path = "/'Dev1'/'Plain'";
  plain.type = kI32;
  plain.count = 4;
  Bytes both = raw;  // the raw data start at byte 146
  both.append(raw);
  CHECK(error_of({daqmx_channel("/'Dev1'/'T'", 4, {{5, 0, 0, 0}}, {4}, false), plain}, both) ==
        "mem.tdms: segment 1 (byte 146): a segment mixing DAQmx raw data with other raw data is "
        "not supported");
}

TEST_CASE("TDMS DAQmx: import --keep-raw keeps the raw counts beside the scaled values",
          "[tdms][daqmx][cli]") {
  const std::vector<std::uint8_t> bytes = daqmx_file(true);
  const testing::TempDir dir("tdms_daqmx_raw");
  const std::string tdms = (dir / "daqmx.tdms").string();
  std::ofstream(tdms, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  const testing::DoorbenchRun run = testing::run_doorbench_shell(
      "import '" + tdms +
          "' --map 'force=Dev1/Force,angle=Dev1/Angle,incl_V=Dev1/Incl' --keep-raw --out '" +
          (dir / "s.h5").string() + "'",
      dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const Recording recording = session_to_recording(SessionReader(dir / "s.h5"));
  REQUIRE(recording.size() == 3 * kChunk);
  REQUIRE(recording.extra_names ==
          std::vector<std::string>{"incl_V", "force_raw", "angle_raw", "incl_raw"});
  for (int k = 0; k < 3 * kChunk; ++k) {
    INFO("sample " << k);
    CHECK(recording.force_N[k] == Approx(force_N(k)).epsilon(1e-12).margin(1e-15));
    CHECK(recording.extra_columns[1][k] == force_counts(k));
    CHECK(recording.extra_columns[2][k] == angle_counts(k));
    CHECK(recording.extra_columns[3][k] == static_cast<double>(incl_volts(k)));
  }
  // Only for TDMS files.
  const testing::DoorbenchRun csv =
      testing::run_doorbench_shell("import '" + (dir / "r.csv").string() + "' --keep-raw --out '" +
                                       (dir / "c.h5").string() + "'",
                                   dir);
  CHECK(csv.status == 2);
  CHECK(csv.err ==
        "doorbench: --keep-raw is for TDMS files (*.tdms) (see doorbench import --help)\n");
}

}  // namespace doorbench
