#include "idmpc/render/overlay.hpp"

#include <GL/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace idmpc::render {
namespace {

constexpr float kPanelAlpha = 0.55f;  // translucent black behind text and plot

}  // namespace

int text_width(const mjrContext& con, const std::string& text) {
  int w = 0;
  for (unsigned char c : text) w += con.charWidth[c];
  return w;
}

double nice_step(double span, int parts) {
  const double raw = span / std::max(parts, 1);
  if (!(raw > 0) || !std::isfinite(raw)) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double f : {1.0, 2.0, 5.0}) {
    if (f * p >= raw * (1 - 1e-9)) return f * p;
  }
  return 10 * p;
}

// ------------------------------------------------------------------------------- table

TableLayout::TableLayout(const mjrContext& con) : con_(con) {
  pad_ = std::max(4, con.charHeight / 3);
  line_ = con.charHeight + pad_ / 2;
  gap_ = 2 * con.charWidth[static_cast<unsigned char>('M')];
  swatch_size_ = con.charHeight * 3 / 4;
}

void TableLayout::fit(const std::vector<Row>& rows) {
  rows_ = std::max(rows_, static_cast<int>(rows.size()));
  for (const Row& r : rows) {
    swatch_ = swatch_ || r.swatch;
    if (r.cells.size() == 1) {
      span_ = std::max(span_, text_width(con_, r.cells[0].text));
      continue;
    }
    if (columns_.size() < r.cells.size()) columns_.resize(r.cells.size(), 0);
    for (std::size_t c = 0; c < r.cells.size(); ++c) {
      columns_[c] = std::max(columns_[c], text_width(con_, r.cells[c].text));
    }
  }
}

int TableLayout::width() const {
  int columns = 0;
  for (std::size_t c = 0; c < columns_.size(); ++c) columns += columns_[c] + (c ? gap_ : 0);
  const int swatch = swatch_ ? swatch_size_ + pad_ : 0;
  return swatch + std::max(columns, span_) + 2 * pad_;
}

int TableLayout::height() const { return rows_ * line_ + pad_ + pad_ / 2; }

void TableLayout::draw(const std::vector<Row>& rows, int left, int top) const {
  const mjrRect panel{left, top - height(), width(), height()};
  mjr_rectangle(panel, 0, 0, 0, kPanelAlpha);
  const int swatch_w = swatch_ ? swatch_size_ + pad_ : 0;

  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    const int baseline = top - pad_ - static_cast<int>(i + 1) * line_ + pad_ / 2;
    if (r.swatch) {
      // light border, then the colour: dark colours stay visible on the dark panel
      const mjrRect box{left + pad_, baseline + (con_.charHeight - swatch_size_) / 2,
                        swatch_size_, swatch_size_};
      mjr_rectangle(box, 0.9f, 0.9f, 0.9f, 1);
      const mjrRect fill{box.left + 1, box.bottom + 1, box.width - 2, box.height - 2};
      mjr_rectangle(fill, r.swatch_rgb[0], r.swatch_rgb[1], r.swatch_rgb[2], 1);
    }
    // mjr_text places text relative to the current viewport: make it the panel
    glViewport(panel.left, panel.bottom, panel.width, panel.height);
    int x = left + pad_ + swatch_w;
    for (std::size_t c = 0; c < r.cells.size(); ++c) {
      const Cell& cell = r.cells[c];
      const int column = r.cells.size() == 1 ? span_ : columns_[c];
      const int cx = cell.right ? x + column - text_width(con_, cell.text) : x;
      mjr_text(mjFONT_NORMAL, cell.text.c_str(), &con_,
               static_cast<float>(cx - panel.left) / static_cast<float>(panel.width),
               static_cast<float>(baseline - panel.bottom) / static_cast<float>(panel.height),
               cell.rgb[0], cell.rgb[1], cell.rgb[2]);
      x += column + gap_;
    }
  }
}

// ------------------------------------------------------------------------------- plot

TimePlot::TimePlot(const std::string& title, double t0, double t1, std::vector<PlotCurve> curves)
    : fig_(std::make_unique<mjvFigure>()), curves_(std::move(curves)) {
  if (curves_.size() > static_cast<std::size_t>(mjMAXLINE)) {
    throw std::invalid_argument("TimePlot: expected at most " + std::to_string(mjMAXLINE) +
                                " curves, got " + std::to_string(curves_.size()));
  }
  // curves are drawn as line segments (two points each): at most kPlotMaxSamples samples, each
  // the largest of its run of consecutive points
  const auto max_samples = static_cast<std::size_t>(kPlotMaxSamples);
  for (auto& curve : curves_) {
    auto& points = curve.points;
    if (points.size() <= max_samples) continue;
    std::vector<std::array<float, 2>> thinned;
    for (std::size_t i = 0; i < max_samples; ++i) {
      const auto n = points.size();
      const auto from = points.begin() + static_cast<std::ptrdiff_t>(i * n / max_samples);
      const auto to = points.begin() + static_cast<std::ptrdiff_t>((i + 1) * n / max_samples);
      thinned.push_back(*std::max_element(
          from, to, [](const auto& p, const auto& q) { return p[1] < q[1]; }));
    }
    points.swap(thinned);
  }

  mjvFigure& fig = *fig_;
  mjv_defaultFigure(&fig);
  fig.flg_extend = 0;
  fig.flg_legend = 0;
  fig.flg_selection = 1;
  fig.flg_barplot = 1;  // GL_LINES: segment pairs, which allows dashes
  fig.flg_ticklabel[0] = 1;
  fig.flg_ticklabel[1] = 1;
  fig.linewidth = 2;
  const float figure_rgba[4] = {0, 0, 0, kPanelAlpha};
  const float pane_rgba[4] = {0.05f, 0.05f, 0.07f, 0.6f};
  std::copy(figure_rgba, figure_rgba + 4, fig.figurergba);
  std::copy(pane_rgba, pane_rgba + 4, fig.panergba);
  std::snprintf(fig.title, sizeof(fig.title), "%s", title.c_str());
  std::snprintf(fig.xlabel, sizeof(fig.xlabel), "%s", "t [s]");
  std::snprintf(fig.xformat, sizeof(fig.xformat), "%s", "%.3g");
  std::snprintf(fig.yformat, sizeof(fig.yformat), "%s", "%.3g");
  std::snprintf(fig.minwidth, sizeof(fig.minwidth), "%s", "0000");
  // mjr_figure draws line 0 last (on top): later curves get lower indices
  for (std::size_t i = 0; i < curves_.size(); ++i) {
    const Rgb& rgb = curves_[i].rgb;
    std::copy(rgb.begin(), rgb.end(), fig.linergb[curves_.size() - 1 - i]);
  }

  // time axis ends on a round tick
  const double span = std::max(t1 - t0, 1e-3);
  const double x_step = nice_step(span, 5);
  const int x_ticks = std::max(1, static_cast<int>(std::ceil(span / x_step - 1e-9)));
  fig.range[0][0] = static_cast<float>(t0);
  fig.range[0][1] = static_cast<float>(t0 + x_ticks * x_step);
  fig.gridsize[0] = x_ticks + 1;

  // value axis from 0 to a round value above the largest value: a short peak is what a
  // reader must not miss
  double largest = 0;
  for (const auto& curve : curves_) {
    for (const auto& p : curve.points) {
      if (std::isfinite(p[1])) largest = std::max(largest, static_cast<double>(p[1]));
    }
  }
  const double top = largest > 0 ? 1.05 * largest : 1;
  const double y_step = nice_step(top, 4);
  const int y_ticks = std::max(1, static_cast<int>(std::ceil(top / y_step - 1e-9)));
  fig.range[1][0] = 0;
  fig.range[1][1] = static_cast<float>(y_ticks * y_step);
  fig.gridsize[1] = y_ticks + 1;
}

float TimePlot::value_top() const { return fig_->range[1][1]; }

void TimePlot::draw(const mjrRect& viewport, double t, const mjrContext& con) {
  mjvFigure& fig = *fig_;
  const float ceiling = fig.range[1][1];
  for (std::size_t i = 0; i < curves_.size(); ++i) {
    const PlotCurve& curve = curves_[i];
    const auto& points = curve.points;
    // dashes about 8 pixels long, counted in samples
    int dash = 1;
    if (curve.dashed && points.size() > 1) {
      const double sample_dt = (points.back()[0] - points.front()[0]) /
                               static_cast<double>(points.size() - 1);
      const double axis = std::max(1e-9, static_cast<double>(fig.range[0][1] - fig.range[0][0]));
      const double pixels_per_sample = 0.8 * viewport.width * sample_dt / axis;
      dash = std::max(1, static_cast<int>(std::lround(8 / std::max(pixels_per_sample, 1e-3))));
    }
    float* data = fig.linedata[curves_.size() - 1 - i];
    int n = 0;
    for (std::size_t j = 0; j + 1 < points.size() && points[j + 1][0] <= t + 1e-9; ++j) {
      if (curve.dashed && (j / static_cast<std::size_t>(dash)) % 2 == 1) continue;
      for (const auto& p : {points[j], points[j + 1]}) {
        // points above the axis are clipped to it rather than drawn outside the plot
        data[2 * n] = p[0];
        data[2 * n + 1] = std::min(p[1], ceiling);
        ++n;
      }
    }
    fig.linepnt[curves_.size() - 1 - i] = n;
  }
  fig.selection = static_cast<float>(t);
  mjr_figure(viewport, &fig, &con);
}

}  // namespace idmpc::render
