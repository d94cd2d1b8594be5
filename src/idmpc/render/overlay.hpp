#pragma once
/// @file overlay.hpp
/// @brief 2-D overlays drawn over a rendered frame with MuJoCo's mjr_* functions: a text table
/// on a translucent panel and a time plot.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

namespace idmpc::render {

using Rgb = std::array<float, 3>;

/// @brief One cell of a table row.
struct Cell {
  std::string text;
  Rgb rgb{1, 1, 1};
  bool right = false;  ///< right-aligned in its column
};

/// @brief One table row; a row of one cell spans all columns. An optional colour swatch
/// (a legend entry) is drawn before the first cell.
struct Row {
  std::vector<Cell> cells;
  bool swatch = false;
  Rgb swatch_rgb{1, 1, 1};
};

/// @brief Column widths and panel size of a table, in pixels. Measuring every frame's rows
/// into one layout keeps the panel from jittering as the numbers change.
class TableLayout {
 public:
  explicit TableLayout(const mjrContext& con);
  /// @brief Widens the columns to fit these rows.
  void fit(const std::vector<Row>& rows);
  int width() const;
  int height() const;
  /// @brief Draws rows with the panel's top-left corner at (left, top), pixels from the
  /// bottom-left of the current framebuffer.
  void draw(const std::vector<Row>& rows, int left, int top) const;

 private:
  const mjrContext& con_;
  std::vector<int> columns_;
  int span_ = 0;  // widest single-cell row
  int rows_ = 0;
  bool swatch_ = false;
  int pad_ = 0, line_ = 0, gap_ = 0, swatch_size_ = 0;
};

/// @brief Width in pixels of text in MuJoCo's normal font.
int text_width(const mjrContext& con, const std::string& text);

/// @brief Most samples a TimePlot curve keeps (it draws segments: two MuJoCo line points each).
inline constexpr int kPlotMaxSamples = mjMAXLINEPNT / 2;

/// @brief One curve of a TimePlot: samples (t, value) with t increasing.
struct PlotCurve {
  std::vector<std::array<float, 2>> points;
  Rgb rgb{1, 1, 1};
  bool dashed = false;  ///< dashes let an identical curve underneath show through
};

/// @brief A plot of curves over a fixed time axis with a moving time cursor; later curves are
/// drawn on top of earlier ones. The value axis runs from 0 to a round value above the largest
/// value, so a short peak shows at its full height; a curve of more than kPlotMaxSamples points
/// keeps the largest value of each run of consecutive points.
class TimePlot {
 public:
  /// @param title e.g. "|u| [N m]"; t0, t1 the time axis; at most mjMAXLINE curves
  TimePlot(const std::string& title, double t0, double t1, std::vector<PlotCurve> curves);
  /// @brief Draws the curves up to time t with a cursor at t into `viewport`.
  void draw(const mjrRect& viewport, double t, const mjrContext& con);
  /// @brief The top of the value axis.
  float value_top() const;
  /// @brief The curves as they are drawn (after thinning).
  const std::vector<PlotCurve>& curves() const { return curves_; }

 private:
  std::unique_ptr<mjvFigure> fig_;  // ~800 kB: on the heap
  std::vector<PlotCurve> curves_;
};

/// @brief A round step (1, 2 or 5 times a power of ten) that cuts `span` into about `parts`.
double nice_step(double span, int parts);

}  // namespace idmpc::render
