// Gaps are first-class: scans a recording lost (a ring overflow kept on
// the clock as kGapFillCount) are missing in every reader, never a number; and they cost
// windows, not strokes: the fit leaves out the windows that span a gap and fits
// the rest of the stroke, and every segment left out is named with its reason. A recovered
// session with a 10 ms gap in its third stroke is made the way `recover` makes one: a
// journal of the simulated bench's scans with one block left out, recovered. Its twin
// without the gap is recovered from the same scans.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/record/journal.h"
#include "acquisition/record/recovery.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_csv.h"
#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"
#include "viewer/session_data.h"

namespace {

using namespace doorbench;

constexpr double kGapStart_s = 7.5;  // in the second opening (stroke 3), 6.6 s to 8.7 s
constexpr std::size_t kBlockScans = 10;
constexpr std::size_t kGapScans = 10;

// Writes the journal of `session`'s scans and events as the recorder would, leaving out
// the block of scans starting at `gap_start_s` when `with_gap`, without an end mark (the
// recording was killed), and recovers it into `out`.
void recover_copy(const std::filesystem::path& session, const std::filesystem::path& out,
                  bool with_gap) {
  const SessionReader reader(session);
  JournalHeader header;
  header.metadata = reader.metadata();
  header.channels = reader.channels();
  header.calibrations = reader.calibrations();
  header.scan_rate_hz = header.channels.front().sample_rate_hz;
  header.session_name = out.filename().string();
  header.flush_interval_s = 0.05;
  header.backend = "test copy";
  const std::size_t channels = header.channels.size();
  std::vector<std::vector<double>> raw;
  for (const ChannelInfo& c : header.channels) raw.push_back(reader.read(c.name).raw);
  const std::size_t scans = raw.front().size();
  const auto gap_first = static_cast<std::size_t>(std::llround(kGapStart_s * header.scan_rate_hz));
  const std::filesystem::path journal = journal_path_for(out);
  {
    JournalWriter writer(journal, header, kBlockScans);
    writer.append_start(0, 0);
    std::vector<std::int32_t> counts(channels * kBlockScans);
    for (std::size_t first = 0; first < scans; first += kBlockScans) {
      const std::size_t count = std::min(kBlockScans, scans - first);
      if (with_gap && first == gap_first) continue;  // the writer fell behind: a block lost
      for (std::size_t c = 0; c < channels; ++c) {
        for (std::size_t s = 0; s < count; ++s) {
          counts[c * kBlockScans + s] = static_cast<std::int32_t>(raw[c][first + s]);
        }
      }
      writer.append_scans(first, count, counts.data(), kBlockScans);
    }
    for (const SessionEvent& e : reader.events()) {
      writer.append_event(e.time_s, e.kind, e.channel, e.detail);
    }
    writer.sync();
  }
  RecoverOptions options;
  options.out = out;
  recover_session(journal, options);
}

struct GapSessions {
  testing::TempDir dir{"gaps"};
  std::filesystem::path gapped, whole;
};

// Recorded and recovered once for the test cases of this file (a second or two).
const GapSessions& gap_sessions() {
  static const GapSessions* sessions = [] {
    auto* s = new GapSessions;
    const auto recorded = s->dir / "recorded.h5";
    testing::record_built_in_session(recorded, 18.6, 11, "sensory");
    s->gapped = s->dir / "gapped.h5";
    s->whole = s->dir / "whole.h5";
    recover_copy(recorded, s->gapped, true);
    recover_copy(recorded, s->whole, false);
    return s;
  }();
  return *sessions;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::size_t gap_index() {
  return static_cast<std::size_t>(std::llround(kGapStart_s * 1000.0));
}

}  // namespace

TEST_CASE("Gaps: a session reader gives lost scans as NaN and lists their runs", "[gaps]") {
  const GapSessions& s = gap_sessions();
  const SessionReader reader(s.gapped);
  for (const ChannelInfo& c : reader.channels()) {
    INFO(c.name);
    const ChannelSlice slice = reader.read(c.name);
    const std::vector<double> values = reader.physical(c.name, slice);
    for (std::size_t i = 0; i < values.size(); ++i) {
      const bool in_gap = i >= gap_index() && i < gap_index() + kGapScans;
      if (in_gap) {
        CHECK(std::isnan(values[i]));
      } else if (!std::isfinite(values[i])) {
        FAIL("sample " << i << " outside the gap is " << values[i]);
      }
    }
    const std::vector<LostRun> runs = lost_runs(c, slice);
    REQUIRE(runs.size() == 1);
    CHECK(runs[0].first_index == gap_index());
    CHECK(runs[0].count == kGapScans);
    CHECK(runs[0].first_time_s == Approx(7.5).margin(1e-4));
    CHECK(runs[0].last_time_s == Approx(7.509).margin(1e-4));
  }
}

TEST_CASE("Gaps: export leaves the gap's cells empty and they read back as missing",
          "[gaps][csv]") {
  const GapSessions& s = gap_sessions();
  const Recording recording = session_to_recording(SessionReader(s.gapped));
  std::size_t missing = 0;
  for (std::size_t i = 0; i < recording.size(); ++i) {
    const bool in_gap = i >= gap_index() && i < gap_index() + kGapScans;
    CHECK(std::isnan(recording.force_N[i]) == in_gap);
    CHECK(std::isnan((*recording.rate_rad_s)[i]) == in_gap);
    if (std::isnan(recording.force_N[i])) ++missing;
    CHECK(!(recording.force_N[i] < -1e6));  // never the fill value scaled
  }
  CHECK(missing == kGapScans);

  std::ostringstream text;
  write_recording_csv(text, recording);
  // Every gap row: its time, then empty cells (force, rate, stroke 3, inclinometer).
  CHECK(contains(text.str(), "\n7.5,,,3,\n"));
  // A complete reader refuses them; a recording reader gives them back as missing.
  CHECK_THROWS_WITH(parse_recording_csv(text.str(), "gap.csv"),
                    Catch::Contains("column force_N: empty cell"));
  const Recording back = parse_recording_csv(text.str(), "gap.csv", EmptyCells::kMissing);
  REQUIRE(back.size() == recording.size());
  for (std::size_t i = 0; i < back.size(); ++i) {
    // The fill value scaled would be -2.9e7 N and -1.5e9 rad/s.
    if (std::abs(back.force_N[i]) > 1e4 || std::abs((*back.rate_rad_s)[i]) > 1e2) {
      FAIL("row " << i << ": " << back.force_N[i] << " N, " << (*back.rate_rad_s)[i] << " rad/s");
    }
  }
  CHECK(std::isnan(back.force_N[gap_index()]));
  CHECK(back.force_N[gap_index() - 1] == recording.force_N[gap_index() - 1]);
  // time_s and stroke are never missing.
  CHECK_THROWS_WITH(parse_recording_csv("time_s,force_N,rate_rad_s\n0,1,2\n,1,2\n", "t.csv",
                                        EmptyCells::kMissing),
                    "t.csv:3: column time_s: empty cell (time_s is never missing)");
  CHECK_THROWS_WITH(parse_recording_csv("time_s,force_N,rate_rad_s,stroke\n0,1,2,\n", "t.csv",
                                        EmptyCells::kMissing),
                    "t.csv:2: column stroke: empty cell (stroke is never missing)");
}

TEST_CASE("Gaps: doorbench info lists the gap, export writes empty cells", "[gaps][cli]") {
  const GapSessions& s = gap_sessions();
  const testing::TempDir dir("gaps_cli");
  const testing::DoorbenchRun info = testing::run_doorbench_shell("info " + s.gapped.string(), dir);
  INFO(info.out << info.err);
  REQUIRE(info.status == 0);
  CHECK(contains(info.out,
                 "gaps: 1 (10 samples lost; they read as missing)\n"
                 "       7.500 s to      7.509 s        10 samples  "
                 "force, angle, rate\n"));
  const testing::DoorbenchRun whole = testing::run_doorbench_shell("info " + s.whole.string(), dir);
  CHECK(contains(whole.out, "gaps: 0\n"));

  const auto csv = dir / "gapped.csv";
  const testing::DoorbenchRun exported =
      testing::run_doorbench_shell("export " + s.gapped.string() + " --csv " + csv.string(), dir);
  INFO(exported.err);
  REQUIRE(exported.status == 0);
  const std::string text = testing::read_file(csv);
  CHECK(contains(text, "\n7.509,,,3,\n"));
  CHECK(!contains(text, "-2916"));
  CHECK(!contains(text, "-2.9164"));
}

TEST_CASE("Gaps: preprocessing keeps the stroke without the lost samples and lists the gap",
          "[gaps][preprocessing]") {
  const GapSessions& s = gap_sessions();
  const PreparedData gapped = prepare_session(s.gapped);
  const PreparedData whole = prepare_session(s.whole);
  REQUIRE(gapped.strokes.size() == 6);
  REQUIRE(whole.strokes.size() == 6);
  for (std::size_t k = 0; k < gapped.strokes.size(); ++k) {
    const Stroke& g = gapped.strokes[k];
    const Stroke& w = whole.strokes[k];
    INFO("stroke " << g.id);
    REQUIRE(g.id == w.id);
    if (g.id != 3) {
      CHECK(g.gap_before.empty());
      CHECK(g.time_s == w.time_s);
      continue;
    }
    // The stroke's samples are the whole session's less the 10 lost; the clock jumps there.
    REQUIRE(g.size() + kGapScans == w.size());
    REQUIRE(g.gap_before.size() == 1);
    const auto at = static_cast<std::size_t>(g.gap_before[0]);
    CHECK(g.time_s[at - 1] == Approx(7.499).margin(1e-9));
    CHECK(g.time_s[at] == Approx(7.510).margin(1e-9));
    for (std::size_t i = 0; i < g.size(); ++i) {
      const std::size_t j = i < at ? i : i + kGapScans;
      REQUIRE(g.time_s[i] == w.time_s[j]);
      REQUIRE(g.force_N[i] == w.force_N[j]);
      // The angle across the gap rests on the rate interpolated over it (bridged).
      if (std::abs(g.theta_rad[i] - w.theta_rad[j]) > 2e-5) FAIL("sample " << i);
    }
  }
  std::vector<ExcludedSegment> gaps;
  for (const ExcludedSegment& e : gapped.excluded) {
    if (e.lost_samples) gaps.push_back(e);
  }
  REQUIRE(gaps.size() == 1);
  CHECK(gaps[0].reason ==
        "stroke 3 (opening): recording gap: 10 samples lost from 7.500 s to 7.509 s; the fit "
        "leaves out the windows that span it and fits the rest of the stroke");
  CHECK(gaps[0].start_s == Approx(7.5).margin(1e-9));
  CHECK(gaps[0].end_s == Approx(7.509).margin(1e-9));
}

namespace {

using Spans = std::vector<std::pair<double, double>>;

// Each window's first and last sample times.
Spans window_spans(const PreparedData& data, const std::vector<FitWindow>& windows) {
  Spans spans;
  for (const FitWindow& w : windows) {
    const Stroke& stroke = data.strokes[w.stroke];
    spans.emplace_back(stroke.time_s[w.first], stroke.time_s[w.first + w.count - 1]);
  }
  return spans;
}

// The windows of the fit (disjoint, estimated start states) and of the metrics (shared
// boundaries), cut at the reference door's stops.
std::vector<WindowOptions> both_window_kinds() {
  WindowOptions fit = metric_window_options(FitOptions{}, reference_model(ModelKind::kSensory));
  fit.disjoint = true;
  WindowOptions metric = fit;
  metric.disjoint = false;
  return {fit, metric};
}

}  // namespace

TEST_CASE("Gaps: a 10 ms gap in a stroke costs only the windows that span it", "[gaps][fitting]") {
  const GapSessions& s = gap_sessions();
  const PreparedData gapped = prepare_session(s.gapped);
  const PreparedData whole = prepare_session(s.whole);
  for (const WindowOptions& options : both_window_kinds()) {
    INFO("disjoint " << options.disjoint);
    const WindowSplit with_gap = split_windows_and_gaps(gapped, options);
    const WindowSplit without = split_windows_and_gaps(whole, options);
    REQUIRE(without.across_gaps.empty());
    // The windows without the gap that overlap the lost samples (7.500 to 7.509 s).
    Spans touched, untouched;
    for (const auto& span : window_spans(whole, without.windows)) {
      (span.first <= 7.509 + 1e-9 && span.second >= 7.5 - 1e-9 ? touched : untouched)
          .push_back(span);
    }
    REQUIRE(touched.size() == 1);
    CHECK(with_gap.across_gaps.size() == touched.size());
    CHECK(with_gap.windows.size() == without.windows.size() - touched.size());
    // Every other window, of stroke 3 and of the others, is fitted as without the gap.
    CHECK(window_spans(gapped, with_gap.windows) == untouched);
    // The window left out is the one that overlapped the gap, its last sample the first
    // after it.
    const Spans lost = window_spans(gapped, with_gap.across_gaps);
    REQUIRE(lost.size() == 1);
    CHECK(lost[0].first == touched[0].first);
    CHECK(lost[0].second == touched[0].second);
  }
  // Named for the user, with the gap's place in the stroke.
  const std::vector<ExcludedSegment> named =
      gap_window_exclusions(gapped, both_window_kinds().front());
  REQUIRE(named.size() == 1);
  CHECK(named[0].reason ==
        "stroke 3 (opening): the window from 7.405 s to 7.605 s spans the recording gap from "
        "7.499 s to 7.510 s and is not fitted");
}

TEST_CASE("Gaps: the fit uses every window the gap does not span", "[gaps][fitting]") {
  const GapSessions& s = gap_sessions();
  const PreparedData gapped = prepare_session(s.gapped);
  const PreparedData whole = prepare_session(s.whole);
  FitOptions options;
  options.cross_validation_folds = 0;
  const DoorModel start = reference_model(ModelKind::kSensory);
  const FitResult a = fit_model(start, gapped, options);
  const FitResult b = fit_model(start, whole, options);
  WindowOptions windows = metric_window_options(options, start);
  windows.disjoint = true;
  CHECK(a.summary.windows == split_windows(gapped, windows).size());
  CHECK(a.summary.windows + 1 == b.summary.windows);
  CHECK(a.summary.strokes == 6);
  REQUIRE(a.summary.parameters.size() == b.summary.parameters.size());
  for (std::size_t i = 0; i < a.summary.parameters.size(); ++i) {
    const FittedParameter& p = a.summary.parameters[i];
    const FittedParameter& q = b.summary.parameters[i];
    INFO(p.name << ": " << p.value << " +- " << p.uncertainty << " and " << q.value << " +- "
                << q.uncertainty);
    REQUIRE(std::isfinite(p.value));
    if (!q.free) {
      CHECK(p.value == q.value);
      continue;
    }
    // One window of 67 fewer: the estimates move by a small fraction of their uncertainty
    // (measured: 0.08 at most, theta4).
    CHECK(std::abs(p.value - q.value) <= 0.25 * q.uncertainty);
  }
  // The metrics count only samples of windows fitted (the left-out window's 200 samples are
  // not errors of 0).
  CHECK(a.summary.fitted.window.count < b.summary.fitted.window.count);
}

TEST_CASE("Gaps: the same gap as a jump of the clock (rows missing from a CSV)",
          "[gaps][preprocessing][csv]") {
  const GapSessions& s = gap_sessions();
  Recording recording = session_to_recording(SessionReader(s.whole));
  const auto first = static_cast<std::ptrdiff_t>(gap_index());
  const auto end = first + static_cast<std::ptrdiff_t>(kGapScans);
  auto erase = [&](std::vector<double>& column) {
    column.erase(column.begin() + first, column.begin() + end);
  };
  erase(recording.time_s);
  erase(recording.force_N);
  erase(*recording.rate_rad_s);
  for (std::vector<double>& column : recording.extra_columns) erase(column);
  if (recording.angle_rad) erase(*recording.angle_rad);
  if (recording.stroke)
    recording.stroke->erase(recording.stroke->begin() + first, recording.stroke->begin() + end);
  const PreparedData jumped = prepare(recording);
  const PreparedData lost = prepare_session(s.gapped);
  REQUIRE(jumped.strokes.size() == 6);
  const Stroke& stroke = jumped.strokes[2];
  REQUIRE(stroke.gap_before == lost.strokes[2].gap_before);
  CHECK(stroke.time_s == lost.strokes[2].time_s);
  std::vector<std::string> reasons;
  for (const ExcludedSegment& e : jumped.excluded) reasons.push_back(e.reason);
  CHECK(reasons == std::vector<std::string>{
                       "stroke 3 (opening): gap in time_s: no sample from 7.499 s to 7.510 s; the "
                       "fit leaves out the windows that span it and fits the rest of the stroke"});
  const WindowOptions options = both_window_kinds().front();
  CHECK(window_spans(jumped, split_windows(jumped, options)) ==
        window_spans(lost, split_windows(lost, options)));
}

TEST_CASE("Gaps: doorbench fit names every segment it leaves out, with its reason",
          "[gaps][cli][fitting]") {
  const GapSessions& s = gap_sessions();
  const testing::TempDir dir("gaps_fit");
  const auto out = dir / "fit";
  const testing::DoorbenchRun run = testing::run_doorbench_shell(
      "fit '" + s.gapped.string() + "' --folds 0 --out '" + out.string() + "'", dir);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const std::string gap_line =
      "excluded 7.500 s to 7.509 s: stroke 3 (opening): recording gap: 10 samples lost from "
      "7.500 s to 7.509 s; the fit leaves out the windows that span it and fits the rest of the "
      "stroke";
  const std::string window_line =
      "excluded 7.405 s to 7.605 s: stroke 3 (opening): the window from 7.405 s to 7.605 s spans "
      "the recording gap from 7.499 s to 7.510 s and is not fitted";
  CHECK(contains(run.err, "  6 strokes, 2 segments excluded\n"));
  CHECK(contains(run.err, "\n  " + window_line + "\n  " + gap_line + "\n"));
  CHECK(contains(run.err,
                 " windows of 0.2 s on 6 strokes (1 window spans a recording gap and "
                 "is left out)\n"));
  const std::string report = testing::read_file(out / "report.md");
  CHECK(contains(report, "excluded (2):\n- " + window_line + "\n- " + gap_line + ".\n\n"));
  const nlohmann::json result = nlohmann::json::parse(testing::read_file(out / "result.json"));
  std::vector<std::string> reasons;
  for (const auto& e : result.at("excluded_segments")) reasons.push_back(e.at("reason"));
  REQUIRE(reasons.size() == 2);
  CHECK("excluded 7.405 s to 7.605 s: " + reasons[0] == window_line);
  CHECK("excluded 7.500 s to 7.509 s: " + reasons[1] == gap_line);
}

TEST_CASE("Gaps: the viewer's channel series break at the gap", "[gaps][viewer]") {
  const GapSessions& s = gap_sessions();
  const viewer::SessionData data = viewer::load_session(s.gapped, {});
  bool checked = false;
  for (const auto& series : data.channel_series) {
    INFO(series->name());
    const std::size_t n = series->size();
    REQUIRE(n > gap_index() + kGapScans);
    for (std::size_t i = 0; i < n; ++i) {
      const double y = series->y(i);
      const bool in_gap = i >= gap_index() && i < gap_index() + kGapScans;
      if (in_gap != std::isnan(y)) FAIL("sample " << i << " is " << y);
    }
    checked = true;
  }
  CHECK(checked);
  // The gap is marked where it starts (the recovery's "gap" event).
  bool marked = false;
  for (const viewer::Marker& m : viewer::event_markers(data, "")) {
    if (contains(m.label, "gap") && std::abs(m.x - kGapStart_s) < 1e-3) marked = true;
  }
  CHECK(marked);
}
