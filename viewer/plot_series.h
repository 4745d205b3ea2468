#pragma once
// The viewer's data model for one curve (no GL, no ImGui): samples with units and the
// min/max decimation that lets a plot draw 10 million samples at interactive rates.
//
// A time series has increasing x (a uniform clock or explicit times); for a visible
// x-range and a plot `width_px` wide, decimate() gives each pixel column the first, last,
// smallest and largest sample that falls in it, exactly. A min/max pyramid built once per
// series (blocks of kPyramidBlock samples, then pairs of blocks, …) answers each column in
// O(kPyramidBlock + log n), so a frame costs O(width · log n), whatever the zoom.
//
// An x–y series (a force–angle loop) has x in any order; it is drawn point by point, with
// consecutive points that land in the same pixel merged (xy_polyline()).
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace doorbench::viewer {

struct Rgba {
  std::uint8_t r = 0, g = 0, b = 0, a = 255;
  bool operator==(const Rgba&) const = default;
};

// Min and max of blocks of samples, level by level: level 0 blocks are kPyramidBlock
// samples, level k blocks are 2^k level-0 blocks.
class MinMaxPyramid {
 public:
  static constexpr std::size_t kPyramidBlock = 16;
  MinMaxPyramid() = default;
  explicit MinMaxPyramid(const std::vector<double>& y);
  // Min and max of y[begin, end) (begin < end <= y.size(), y the vector it was built on).
  // NaN samples are skipped; an all-NaN range gives min = +inf, max = -inf.
  void range(const std::vector<double>& y, std::size_t begin, std::size_t end, double& min,
             double& max) const;

 private:
  std::vector<std::vector<double>> min_;  // min_[level][block]
  std::vector<std::vector<double>> max_;
};

class Series {
 public:
  // A time series on a uniform clock: x_i = x0 + i · dx (dx > 0).
  static Series uniform(std::string name, std::string unit, double x0, double dx,
                        std::vector<double> y);
  // A time series with explicit, non-decreasing x (same length as y).
  static Series timed(std::string name, std::string unit, std::vector<double> x,
                      std::vector<double> y);
  // An x–y curve: x in any order (e.g. angle), y (e.g. force).
  static Series xy(std::string name, std::string x_unit, std::string unit, std::vector<double> x,
                   std::vector<double> y);

  const std::string& name() const { return name_; }
  const std::string& unit() const { return unit_; }  // of y
  const std::string& x_unit() const { return x_unit_; }
  bool is_xy() const { return kind_ == Kind::kXy; }
  bool is_uniform() const { return kind_ == Kind::kUniform; }
  std::size_t size() const { return y_.size(); }
  double x(std::size_t i) const { return kind_ == Kind::kUniform ? x0_ + double(i) * dx_ : x_[i]; }
  double y(std::size_t i) const { return y_[i]; }
  const std::vector<double>& ys() const { return y_; }
  // A copy with x moved by dx (time series: the same samples on a shifted clock) and a new
  // name; the colour is kept.
  Series shifted(double dx, std::string name) const;

  Rgba colour{};
  // How the widget draws the line: its width and stacking (higher layers on top); set from
  // the curve's meaning by style_series() (viewer/session_data.h, analysis/report/plot_style.h).
  float width_px = 2.0f;
  int layer = 0;
  // Samples with x in [x_min, x_max], as [begin, end) (time series only).
  void index_range(double x_min, double x_max, std::size_t& begin, std::size_t& end) const;
  // The first index with x >= value (time series only), size() when none.
  std::size_t lower_index(double value) const;
  // Min and max of y[begin, end) through the pyramid.
  void y_range(std::size_t begin, std::size_t end, double& min, double& max) const;
  // Finite min and max of x and y over all samples (for "fit to data").
  void bounds(double& x_min, double& x_max, double& y_min, double& y_max) const;
  // The sample nearest to x (time series: by x; x–y: by distance with x and y scaled by
  // x_scale and y_scale, e.g. pixels per unit). size() when empty.
  std::size_t nearest(double x, double y = 0.0, double x_scale = 1.0, double y_scale = 1.0) const;

 private:
  enum class Kind { kUniform, kTimed, kXy };
  Series(std::string name, std::string x_unit, std::string unit, Kind kind);
  void build();

  std::string name_;
  std::string x_unit_;
  std::string unit_;
  Kind kind_ = Kind::kUniform;
  double x0_ = 0.0;
  double dx_ = 1.0;
  std::vector<double> x_;  // timed and x–y only
  std::vector<double> y_;
  MinMaxPyramid pyramid_;  // time series only
};

// One pixel column of a decimated time series.
struct Column {
  std::size_t count = 0;  // samples in it; 0: nothing to draw
  double first = 0.0, last = 0.0;
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
};

// Column c covers x in [edge(c), edge(c+1)) with edge(c) = x_min + (x_max − x_min) · (c /
// width_px); the last column ends at x_max inclusive. Throws std::invalid_argument for an x–y
// series, width_px 0 or an empty or non-finite range.
std::vector<Column> decimate(const Series& series, double x_min, double x_max,
                             std::size_t width_px);
// The same into `columns` (resized to width_px), reusing its memory frame after frame.
void decimate_into(const Series& series, double x_min, double x_max, std::size_t width_px,
                   std::vector<Column>& columns);

}  // namespace doorbench::viewer
