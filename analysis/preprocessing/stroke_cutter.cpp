// The stroke cutter of prepare() (docs/preprocessing.md, "Strokes"): the motion's
// segments, or the recording's stroke column, cut into strokes; those with faults, an
// unknown angle or too short left out and listed.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "analysis/preprocessing/internal/prepare_stages.h"
#include "core/units.h"

namespace doorbench {

using namespace preprocessing_detail;

namespace {

std::string describe_faults(std::uint8_t kinds, double gyro_limit_rad_s) {
  std::string out;
  auto add = [&out](const std::string& what) { out += (out.empty() ? "" : ", ") + what; };
  if (kinds & kSaturated) {
    add("gyroscope saturated (|rate_rad_s| >= " + text(gyro_limit_rad_s / kRadPerDeg, 4) +
        " deg/s)");
  }
  if (kinds & kRateNonFinite) add("non-finite rate_rad_s");
  if (kinds & kAngleNonFinite) add("non-finite angle_rad");
  if (kinds & kForceNonFinite) add("non-finite force_N");
  if (kinds & kGapBefore) add("gap in time_s");
  if (kinds & kLost) add("recording gap (samples lost)");
  if (kinds & kImpossible) add("physically impossible values");
  return out;
}

}  // namespace

namespace preprocessing_detail {

// Motion segments of ω (see PreprocessingOptions, segmentation). Segments too short to be
// strokes go to `excluded`. Ids are 1, 2, … in time order.
std::vector<Candidate> segment_strokes(const std::vector<double>& time_s,
                                       const std::vector<double>& theta,
                                       const std::vector<double>& omega, double edge_rate,
                                       const PreprocessingOptions& options,
                                       std::vector<ExcludedSegment>& excluded) {
  const std::size_t n = time_s.size();
  struct Run {
    std::size_t lo, hi;
    int sign;
  };
  std::vector<Run> runs;
  std::size_t i = 0;
  while (i < n) {
    if (std::abs(omega[i]) <= options.motion_rate_rad_s) {
      ++i;
      continue;
    }
    const int sign = omega[i] > 0 ? 1 : -1;
    std::size_t lo = i, hi = i;
    while (hi + 1 < n && sign * omega[hi + 1] > options.motion_rate_rad_s) ++hi;
    i = hi + 1;
    while (lo > 0 && sign * omega[lo - 1] > edge_rate) --lo;
    while (hi + 1 < n && sign * omega[hi + 1] > edge_rate) ++hi;
    if (!runs.empty() && runs.back().sign == sign && lo <= runs.back().hi + 1) {
      runs.back().hi = std::max(runs.back().hi, hi);
    } else {
      runs.push_back({lo, hi, sign});
    }
    i = std::max(i, hi + 1);
  }

  auto net = [&](const Run& r) { return theta[r.hi] - theta[r.lo]; };
  auto tiny = [&](const Run& r) { return std::abs(net(r)) < options.min_stroke_angle_rad; };
  std::vector<Run> merged;
  for (const Run& run : runs) {
    if (!merged.empty()) {
      Run& current = merged.back();
      const double gap_s = time_s[run.lo] - time_s[current.hi];
      const bool same_way = (net(current) > 0) == (net(run) > 0);
      if (gap_s < options.merge_gap_s && (same_way || tiny(current) || tiny(run))) {
        current.hi = run.hi;
        continue;
      }
    }
    merged.push_back(run);
  }

  std::vector<Run> kept;
  for (const Run& run : merged) {
    const double duration_s = time_s[run.hi] - time_s[run.lo];
    const double angle = net(run);
    if (duration_s < options.min_stroke_duration_s ||
        std::abs(angle) < options.min_stroke_angle_rad) {
      excluded.push_back({time_s[run.lo], time_s[run.hi],
                          "movement too short for a stroke (" + text(duration_s) + " s, " +
                              text(angle / kRadPerDeg) +
                              " deg; a stroke needs >= " + text(options.min_stroke_duration_s) +
                              " s and >= " + text(options.min_stroke_angle_rad / kRadPerDeg) +
                              " deg)"});
    } else {
      kept.push_back(run);
    }
  }

  // The margins of rest before and after, never past the middle of the gap to a neighbour.
  std::vector<Candidate> strokes;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    std::size_t lo = first_at_or_after(time_s, time_s[kept[k].lo] - options.stroke_margin_s);
    std::size_t hi = last_at_or_before(time_s, time_s[kept[k].hi] + options.stroke_margin_s);
    if (k > 0) lo = std::max(lo, (kept[k - 1].hi + kept[k].lo) / 2 + 1);
    if (k + 1 < kept.size()) hi = std::min(hi, (kept[k].hi + kept[k + 1].lo) / 2);
    strokes.push_back({{lo, hi}, static_cast<int>(k + 1)});
  }
  return strokes;
}

std::vector<Candidate> strokes_from_column(const std::vector<int>& stroke) {
  std::vector<Candidate> strokes;
  std::size_t i = 0;
  while (i < stroke.size()) {
    if (stroke[i] == 0) {
      ++i;
      continue;
    }
    std::size_t last = i;
    while (last + 1 < stroke.size() && stroke[last + 1] == stroke[i]) ++last;
    strokes.push_back({{i, last}, stroke[i]});
    i = last + 1;
  }
  return strokes;
}

}  // namespace preprocessing_detail

namespace {

// Cuts the strokes out of the motion: one candidate at a time (cut()), leaving out (and
// listing) those with faults, with an unknown angle, or too short; then lists the faulty
// samples outside every stroke (list_faults_outside()).
class StrokeCutter {
 public:
  StrokeCutter(const Input& in, const Motion& motion, const std::vector<Anchor>& anchors,
               const PreprocessingOptions& options, PreparedData& data,
               std::vector<ExcludedSegment>& excluded)
      : in_(in),
        t_(in.t),
        motion_(motion),
        anchors_(anchors),
        options_(options),
        data_(data),
        excluded_(excluded),
        covered_(in.size(), false) {}

  void cut(const Candidate& candidate);
  void list_faults_outside();

 private:
  // The candidate's name, direction and faults (a gap before its first sample is outside).
  struct Faults {
    std::uint8_t kinds = 0;
    std::size_t count = 0;
    std::size_t first = 0;
  };
  std::uint8_t fault_at(const Range& r, std::size_t i) const {
    return i == r.first ? static_cast<std::uint8_t>(in_.fault[i] & ~kGapBefore) : in_.fault[i];
  }
  Faults faults_in(const Range& r) const;
  bool angle_known(std::size_t first, std::size_t last) const;
  bool long_enough(const Range& piece) const {
    return t_[piece.last] - t_[piece.first] >= options_.min_stroke_duration_s &&
           std::abs(motion_.theta[piece.last] - motion_.theta[piece.first]) >=
               options_.min_stroke_angle_rad;
  }
  bool lost(std::size_t i) const { return (in_.fault[i] & kLost) != 0; }
  // A sample that ends a usable part: one not lost with a fault other than a gap before it.
  bool breaks(const Range& r, std::size_t i) const {
    return !lost(i) && (fault_at(r, i) & ~kGapBefore) != 0;
  }
  std::optional<Range> best_part(const Range& segment, std::optional<Range> best) const;
  std::optional<Range> keep_good_part(const Range& r, const std::string& name,
                                      const Faults& faults);
  void list_gaps(const Range& part, const std::string& name);
  std::string reason_to_leave_out(const Range& r, const std::string& name, double net) const;
  void keep(const Candidate& candidate, const Range& r, StrokeDirection direction);

  const Input& in_;
  const std::vector<double>& t_;
  const Motion& motion_;
  const std::vector<Anchor>& anchors_;
  const PreprocessingOptions& options_;
  PreparedData& data_;
  std::vector<ExcludedSegment>& excluded_;
  std::vector<bool> covered_;
};

StrokeCutter::Faults StrokeCutter::faults_in(const Range& r) const {
  Faults faults;
  faults.first = in_.size();
  for (std::size_t i = r.first; i <= r.last; ++i) {
    // A lost sample's channels are all missing: the loss says it.
    const std::uint8_t f = lost(i) ? static_cast<std::uint8_t>(kLost) : fault_at(r, i);
    if (f == 0) continue;
    faults.kinds |= f;
    ++faults.count;
    faults.first = std::min(faults.first, i);
  }
  return faults;
}

// Whether the angle on [first, last] is known: joined to an anchor by a known rate. Before
// the first anchor and after the last the angle is only as good as the rate between the
// stroke and that anchor (with the rate only, that is everywhere).
bool StrokeCutter::angle_known(std::size_t first, std::size_t last) const {
  const bool anchored = in_.mode == Mode::kFused || in_.mode == Mode::kRateOnly;
  if (!anchored) return true;
  const Anchor* left = nullptr;
  const Anchor* right = nullptr;
  for (const Anchor& anchor : anchors_) {
    if (anchor.index <= first) left = &anchor;
    if (anchor.index >= last && right == nullptr) right = &anchor;
  }
  return (left != nullptr && in_.unknown[last] == in_.unknown[left->index]) ||
         (right != nullptr && in_.unknown[right->index] == in_.unknown[first]);
}

// The better of `best` and the parts of `segment` (no fault but gaps in it; it starts and
// ends with a sample not lost): the whole segment when the angle is known on every piece
// between its gaps (the fit then leaves out only the windows that span a gap), else its
// longest gap-free piece whose angle is known. Long enough for a stroke, or not taken.
std::optional<Range> StrokeCutter::best_part(const Range& segment,
                                             std::optional<Range> best) const {
  std::vector<Range> pieces;
  for (std::size_t i = segment.first; i <= segment.last;) {
    if (lost(i)) {
      ++i;
      continue;
    }
    Range piece{i, i};
    while (piece.last + 1 <= segment.last && !lost(piece.last + 1) &&
           !(in_.fault[piece.last + 1] & kGapBefore)) {
      ++piece.last;
    }
    pieces.push_back(piece);
    i = piece.last + 1;
  }
  const bool across_gaps = std::all_of(pieces.begin(), pieces.end(), [&](const Range& piece) {
    return angle_known(piece.first, piece.last);
  });
  std::vector<Range> candidates = across_gaps ? std::vector<Range>{segment} : pieces;
  for (const Range& part : candidates) {
    if ((across_gaps || angle_known(part.first, part.last)) && long_enough(part) &&
        (!best || part.last - part.first > best->last - best->first)) {
      best = part;
    }
  }
  return best;
}

// A stroke with faults: a brisk stroke saturates the gyroscope for part of its course, a
// ring overflow loses scans. Split at its faulty samples (not at gaps: lost scans and jumps
// of the clock), the best part (best_part) is kept and the rest listed, each gap kept inside
// it too (list_gaps). nullopt: no part is.
std::optional<Range> StrokeCutter::keep_good_part(const Range& r, const std::string& name,
                                                  const Faults& faults) {
  const std::string described = describe_faults(faults.kinds, in_.saturation_limit) + " in " +
                                std::to_string(faults.count) + " samples from " +
                                seconds(t_[faults.first]);
  const bool any_lost = (faults.kinds & kLost) != 0;
  std::optional<Range> best;
  std::size_t i = r.first;
  while (i <= r.last) {
    if (breaks(r, i) || lost(i)) {
      ++i;
      continue;
    }
    Range segment{i, i};
    while (segment.last + 1 <= r.last && !breaks(r, segment.last + 1)) ++segment.last;
    i = segment.last + 1;
    while (lost(segment.last)) --segment.last;  // it starts with a sample not lost
    best = best_part(segment, best);
  }
  if (!best) {
    excluded_.push_back({t_[r.first], t_[r.last], name + ": " + described, any_lost});
    return std::nullopt;
  }
  if (best->first > r.first) {
    excluded_.push_back({t_[r.first], t_[best->first - 1],
                         name + ", before the part kept: " + described, any_lost});
  }
  if (best->last < r.last) {
    excluded_.push_back(
        {t_[best->last + 1], t_[r.last], name + ", after the part kept: " + described, any_lost});
  }
  list_gaps(*best, name);
  return best;
}

// Each gap inside the part kept, listed: its samples are missing, and the fit leaves out the
// windows that span it (analysis/fit/fit_windows.h); the rest of the stroke is fitted.
void StrokeCutter::list_gaps(const Range& part, const std::string& name) {
  const std::string fitted =
      "; the fit leaves out the windows that span it and fits the rest "
      "of the stroke";
  for (std::size_t i = part.first + 1; i <= part.last; ++i) {
    if (lost(i)) {
      std::size_t last = i;
      while (lost(last + 1)) ++last;
      excluded_.push_back({t_[i], t_[last],
                           name + ": recording gap: " + std::to_string(last - i + 1) +
                               " samples lost from " + seconds(t_[i]) + " to " + seconds(t_[last]) +
                               fitted,
                           true});
      i = last;
    } else if (in_.fault[i] & kGapBefore) {
      excluded_.push_back({t_[i - 1], t_[i],
                           name + ": gap in time_s: no sample from " + seconds(t_[i - 1]) + " to " +
                               seconds(t_[i]) + fitted,
                           true});
    }
  }
}

// Why a fault-free stroke is left out: its angle is unknown, or it is too short ("" when
// it is kept).
std::string StrokeCutter::reason_to_leave_out(const Range& r, const std::string& name,
                                              double net) const {
  if (!angle_known(r.first, r.last)) {
    return name +
           ": angle unknown: the gyroscope's rate is unknown (saturated, non-finite "
           "or a gap) between this stroke and the " +
           std::string(in_.mode == Mode::kFused ? "nearest inclinometer anchor"
                                                : "still period where theta = 0");
  }
  if (!long_enough(r)) {
    return name + ": too short (" + text(t_[r.last] - t_[r.first]) + " s, " +
           text(net / kRadPerDeg) +
           " deg; a stroke needs >= " + text(options_.min_stroke_duration_s) +
           " s and >= " + text(options_.min_stroke_angle_rad / kRadPerDeg) + " deg)";
  }
  return "";
}

void StrokeCutter::keep(const Candidate& candidate, const Range& r, StrokeDirection direction) {
  Stroke stroke;
  stroke.id = candidate.id;
  stroke.direction = direction;
  // Lost samples are left out (their values were only bridged), so the clock jumps there;
  // each gap is marked where it ends.
  bool gap = false;
  for (std::size_t i = r.first; i <= r.last; ++i) {
    if (lost(i)) {
      gap = true;
      continue;
    }
    if (i > r.first && (gap || (in_.fault[i] & kGapBefore))) {
      stroke.gap_before.push_back(static_cast<int>(stroke.time_s.size()));
    }
    gap = false;
    stroke.time_s.push_back(t_[i]);
    stroke.force_N.push_back(in_.force[i]);
    stroke.theta_rad.push_back(motion_.theta[i]);
    stroke.omega_rad_s.push_back(motion_.omega[i]);
  }
  data_.strokes.push_back(std::move(stroke));
}

void StrokeCutter::cut(const Candidate& candidate) {
  Range r = candidate.range;
  for (std::size_t i = r.first; i <= r.last; ++i) covered_[i] = true;
  const double net = motion_.theta[r.last] - motion_.theta[r.first];
  const StrokeDirection direction = net > 0 ? StrokeDirection::kOpening : StrokeDirection::kClosing;
  const std::string name = "stroke " + std::to_string(candidate.id) + " (" +
                           (direction == StrokeDirection::kOpening ? "opening" : "closing") + ")";
  const Faults faults = faults_in(r);
  if (faults.kinds != 0) {
    const std::optional<Range> part = keep_good_part(r, name, faults);
    if (!part) return;
    r = *part;
  } else if (const std::string reason = reason_to_leave_out(r, name, net); !reason.empty()) {
    excluded_.push_back({t_[r.first], t_[r.last], reason});
    return;
  }
  keep(candidate, r, direction);
}

void StrokeCutter::list_faults_outside() {
  const std::size_t n = in_.size();
  std::size_t i = 0;
  while (i < n) {
    const std::uint8_t f = covered_[i] ? 0 : in_.fault[i];
    if (f == 0) {
      ++i;
      continue;
    }
    std::size_t last = i;
    std::uint8_t kinds = f;
    while (last + 1 < n && !covered_[last + 1] && in_.fault[last + 1] != 0) {
      kinds |= in_.fault[++last];
    }
    const std::size_t first = (f & kGapBefore) && i > 0 ? i - 1 : i;  // a gap starts before
    excluded_.push_back({t_[first], t_[last],
                         "outside the strokes: " + describe_faults(kinds, in_.saturation_limit),
                         (kinds & kLost) != 0});
    i = last + 1;
  }
}

}  // namespace

namespace preprocessing_detail {

void cut_strokes(const Input& in, const Motion& motion, const std::vector<Anchor>& anchors,
                 const std::vector<Candidate>& candidates, const PreprocessingOptions& options,
                 PreparedData& data, std::vector<ExcludedSegment>& excluded) {
  StrokeCutter cutter(in, motion, anchors, options, data, excluded);
  for (const Candidate& candidate : candidates) cutter.cut(candidate);
  cutter.list_faults_outside();
}

}  // namespace preprocessing_detail

}  // namespace doorbench
