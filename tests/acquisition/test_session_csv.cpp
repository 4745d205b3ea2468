// Sessions to and from the CSV exchange format: import then export gives back the values.
#include <catch2/catch.hpp>
#include <filesystem>

#include "acquisition/session/session_csv.h"
#include "fixtures/temp_dir.h"

namespace {

using namespace doorbench;

// A file in this process's scratch folder (removed when the process ends).
std::filesystem::path fresh_path(const std::string& name) {
  static const doorbench::testing::TempDir scratch("session_csv");
  // Catch2 runs a test case again for each SECTION in the same process: start afresh.
  std::filesystem::remove(scratch / name);
  return scratch / name;
}

}  // namespace

TEST_CASE("Session CSV: import then export returns the recording", "[session_csv]") {
  const std::string csv =
      "# handle_radius_m: 0.55\n"
      "# source: a spreadsheet\n"
      "time_s,force_N,angle_rad,rate_rad_s,stroke,pot_V,gyro2_rad_s\n"
      "0.000,0.1,0.0,0.0,0,1.5,0.01\n"
      "0.001,12.25,0.001,0.5,1,1.6,0.02\n"
      "0.002,30.5,0.002,0.75,1,1.7,0.03\n"
      "0.003,-3.0,0.003,0.25,0,1.8,0.04\n"
      "0.004,-20.0,0.002,-0.5,2,1.9,0.05\n"
      "0.005,-1.0,0.001,-0.25,2,2.0,0.06\n";
  const Recording original = parse_recording_csv(csv, "in.csv");
  const auto path = fresh_path("imported.h5");
  SessionMetadata metadata;
  metadata.rig_name = "imported";
  recording_to_session(original, path, metadata);

  const SessionReader session(path);
  CHECK(session.channels().size() == 5);
  CHECK(session.channel("pot_V").unit == "V");
  CHECK(session.channel("gyro2_rad_s").unit == "rad/s");
  CHECK(session.channel("force").sample_rate_hz == Approx(1000.0));

  const Recording back = session_to_recording(session);
  CHECK(back.force_N == original.force_N);  // float64 end to end: exact
  CHECK(*back.angle_rad == *original.angle_rad);
  CHECK(*back.rate_rad_s == *original.rate_rad_s);
  REQUIRE(back.stroke.has_value());
  CHECK(*back.stroke == std::vector<int>{0, 1, 1, 0, 2, 2});
  REQUIRE(back.extra_names.size() == 2);
  CHECK(back.extra_names[0] == "pot_V");
  CHECK(back.extra_names[1] == "gyro2_rad_s");
  CHECK(back.extra_columns[0] == original.extra_columns[0]);
  REQUIRE(back.handle_radius_m.has_value());
  CHECK(*back.handle_radius_m == 0.55);
  for (std::size_t i = 0; i < back.size(); ++i) {
    CHECK(back.time_s[i] == Approx(original.time_s[i]).margin(1e-12));
  }
}

TEST_CASE("Session CSV: irregular times are kept exactly", "[session_csv]") {
  const std::string csv =
      "time_s,force_N,rate_rad_s\n"
      "0.0,1,0.1\n"
      "0.0013,2,0.2\n"
      "0.0021,3,0.3\n"
      "0.0047,4,0.4\n";
  const Recording original = parse_recording_csv(csv, "irregular.csv");
  const auto path = fresh_path("irregular.h5");
  recording_to_session(original, path, SessionMetadata{});
  const SessionReader session(path);
  CHECK(session.channel("force").sample_rate_hz == 0.0);
  const Recording back = session_to_recording(session);
  CHECK(back.time_s == original.time_s);
  CHECK(back.force_N == original.force_N);
  CHECK_FALSE(back.stroke.has_value());
}

TEST_CASE("Session CSV: importing over an existing session is refused", "[session_csv]") {
  const Recording original =
      parse_recording_csv("time_s,force_N,rate_rad_s\n0,1,0\n1,2,0\n", "x.csv");
  const auto path = fresh_path("twice.h5");
  recording_to_session(original, path, SessionMetadata{});
  CHECK_THROWS_WITH(recording_to_session(original, path, SessionMetadata{}),
                    Catch::Matchers::Contains("already exists"));
}

TEST_CASE("Session CSV: stroke ids and regular times survive the round trip", "[session_csv]") {
  // 30 rows at 100 Hz from t = 12.34 s, strokes 3 and 5: 1 / mean interval is not exactly
  // 100 here, and 12.34 + i / 100 is not always the decimal time, so the importer must
  // either find the exact clock or keep the times.
  std::string csv = "time_s,force_N,rate_rad_s,stroke\n";
  for (int i = 0; i < 30; ++i) {
    const int stroke = (i >= 5 && i < 10) ? 3 : (i >= 15 && i < 20) ? 5 : 0;
    csv += std::to_string(12.34 + i * 0.01).substr(0, 5) + "," + std::to_string(i) + ",0," +
           std::to_string(stroke) + "\n";
  }
  const Recording original = parse_recording_csv(csv, "strokes.csv");
  const auto path = fresh_path("strokes.h5");
  recording_to_session(original, path, SessionMetadata{});
  const Recording back = session_to_recording(SessionReader(path));
  CHECK(back.time_s == original.time_s);
  CHECK(*back.stroke == *original.stroke);
}

TEST_CASE("Session CSV: stroke columns from stroke events, in any order", "[session_csv]") {
  const std::vector<double> time_s = {0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7};
  // Out of order; 0.1 + 0.2 is 0.30000000000000004 and still applies at sample 0.3.
  const std::vector<SessionEvent> events = {
      {0.5, "stroke_start", "", "closing"},  {0.1 + 0.2, "stroke_end", "", ""},
      {0.1, "stroke_start", "", "stroke 7"}, {0.6, "stroke_end", "", ""},
      {0.65, "mark", "", "stroke 2"},  // not a stroke event
      {0.7, "stroke_start", "", "opening"},
  };
  const StrokeColumns columns = stroke_columns_from_events(events, time_s);
  CHECK(columns.any_stroke);
  // Stroke 7 keeps its id; the next ones are numbered on from it.
  CHECK(columns.stroke == std::vector<int>{0, 7, 7, 0, 0, 8, 0, 9});
  CHECK(columns.sign == std::vector<int>{1, 1, 1, 1, 1, -1, -1, 1});

  const StrokeColumns none = stroke_columns_from_events({{0.2, "stroke_end", "", ""}}, time_s);
  CHECK_FALSE(none.any_stroke);
  CHECK(none.stroke == std::vector<int>(time_s.size(), 0));
  CHECK(none.sign == std::vector<int>(time_s.size(), 1));
}
