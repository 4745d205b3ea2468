// Export then import: the imported session keeps the channels' names and
// the session's rig, operator, product and start time, so that `info` says the same of both;
// and `info`'s channel table lines up whatever the names' lengths.
#include <algorithm>
#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

using namespace doorbench;

namespace {

// The lines of `text` starting with `prefix`.
std::vector<std::string> lines_starting(const std::string& text, const std::string& prefix) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) lines.push_back(line);
  }
  return lines;
}

// The rows of info's channel table (header first): the lines between "channels:" and the
// next line that does not start with two spaces.
std::vector<std::string> channel_table(const std::string& info) {
  std::vector<std::string> rows;
  std::istringstream in(info);
  bool inside = false;
  for (std::string line; std::getline(in, line);) {
    if (line == "channels:") {
      inside = true;
      continue;
    }
    if (inside && line.rfind("  ", 0) != 0) break;
    if (inside) rows.push_back(line);
  }
  return rows;
}

std::vector<std::string> sorted_channel_names(const std::string& path) {
  const SessionReader reader(path);
  std::vector<std::string> names;
  for (const ChannelInfo& c : reader.channels()) names.push_back(c.name);
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST_CASE("export then import keeps channel names, rig, operator, product and start time",
          "[csv][cli]") {
  testing::TempDir dir("csv_round_trip");
  const std::string session = (dir / "bench.h5").string(), csv = (dir / "bench.csv").string(),
                    imported = (dir / "imported.h5").string();
  auto r = testing::run_doorbench_shell(
      "record --out '" + session + "' --duration-s 3 --operator 'Ann Lee' --product DW-7", dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  r = testing::run_doorbench_shell("export '" + session + "' --csv '" + csv + "'", dir);
  REQUIRE(r.status == 0);
  r = testing::run_doorbench_shell("import '" + csv + "' --out '" + imported + "'", dir);
  REQUIRE(r.status == 0);

  // The bench's inclinometer "angle" is exported as inclinometer_angle_rad, and comes back
  // as "angle" (still an inclinometer).
  const std::vector<std::string> names = sorted_channel_names(session);
  REQUIRE(std::find(names.begin(), names.end(), "angle") != names.end());
  CHECK(sorted_channel_names(imported) == names);
  const SessionReader back(imported);
  CHECK(back.channel("angle").sensor_kind == "inclinometer");

  const std::string info_a = testing::run_doorbench_shell("info '" + session + "'", dir).out;
  const std::string info_b = testing::run_doorbench_shell("info '" + imported + "'", dir).out;
  for (const char* field : {"  rig ", "  operator ", "  product ", "  started "}) {
    INFO(field);
    const auto a = lines_starting(info_a, field), b = lines_starting(info_b, field);
    REQUIRE(a.size() == 1);
    CHECK(b == a);
  }
  CHECK(lines_starting(info_a, "  operator ")[0] == "  operator   Ann Lee");
  // A second round trip gives the same CSV but for its source line.
  const std::string csv2 = (dir / "again.csv").string();
  REQUIRE(
      testing::run_doorbench_shell("export '" + imported + "' --csv '" + csv2 + "'", dir).status ==
      0);
  auto without_source = [](const std::string& path) {
    std::ifstream in(path);
    std::string text, line;
    while (std::getline(in, line)) {
      if (line.rfind("# source:", 0) != 0) text += line + "\n";
    }
    return text;
  };
  CHECK(without_source(csv2) == without_source(csv));
}

TEST_CASE("info's channel table lines up with long channel names", "[csv][cli]") {
  testing::TempDir dir("info_alignment");
  const std::string path = (dir / "long.h5").string();
  {
    SessionMetadata metadata;
    metadata.rig_name = "test";
    SessionWriter writer(path, metadata);
    for (const char* name : {"force", "inclinometer_angle_rad_of_the_door"}) {
      ChannelInfo channel;
      channel.name = name;
      channel.sensor_kind = "imported_from_a_long_source";
      channel.raw_type = RawType::kValues;
      channel.raw_unit = std::string("N");
      channel.unit = std::string("N");
      channel.range_min = -1;
      channel.range_max = 1;
      channel.sample_rate_hz = 10;
      writer.append_values(writer.add_channel(channel), std::vector<double>(5, 0.0));
    }
    writer.close();
  }
  const std::string info = testing::run_doorbench_shell("info '" + path + "'", dir).out;
  const std::vector<std::string> rows = channel_table(info);
  REQUIRE(rows.size() == 3);
  // Every column starts where its header does: a space before it, text at it.
  for (const char* header : {"sensor", "raw", "unit", "calibration"}) {
    const std::size_t at = rows[0].find(std::string(" ") + header) + 1;
    for (std::size_t i = 1; i < rows.size(); ++i) {
      INFO(header << " in row " << rows[i]);
      REQUIRE(rows[i].size() > at);
      CHECK(rows[i][at - 1] == ' ');
      CHECK(rows[i][at] != ' ');
    }
  }
  // Numbers right-aligned under their headers.
  const std::size_t samples_end = rows[0].find("samples") + 7;
  for (std::size_t i = 1; i < rows.size(); ++i) CHECK(rows[i][samples_end - 1] == '5');
}
