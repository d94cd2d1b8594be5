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

TimePlot::TimePlot(const std::string& title, double t0, double t1,
                   std::vector<std::vector<std::array<float, 2>>> curves, std::vector<Rgb> colours)
    : fig_(std::make_unique<mjvFigure>()), curves_(std::move(curves)) {
  if (curves_.size() > static_cast<std::size_t>(mjMAXLINE) || colours.size() < curves_.size()) {
    throw std::invalid_argument("TimePlot: expected at most " + std::to_string(mjMAXLINE) +
                                " curves with a colour each, got " +
                                std::to_string(curves_.size()) + " curves and " +
                                std::to_string(colours.size()) + " colours");
  }
  // keep at most mjMAXLINEPNT samples per curve
  for (auto& curve : curves_) {
    if (curve.size() <= static_cast<std::size_t>(mjMAXLINEPNT)) continue;
    std::vector<std::array<float, 2>> thinned;
    const std::size_t n = static_cast<std::size_t>(mjMAXLINEPNT);
    for (std::size_t i = 0; i < n; ++i) thinned.push_back(curve[i * (curve.size() - 1) / (n - 1)]);
    curve.swap(thinned);
  }

  mjvFigure& fig = *fig_;
  mjv_defaultFigure(&fig);
  fig.flg_extend = 0;
  fig.flg_legend = 0;
  fig.flg_selection = 1;
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
  for (std::size_t i = 0; i < curves_.size(); ++i) {
    std::copy(colours[i].begin(), colours[i].end(), fig.linergb[i]);
  }

  // time axis ends on a round tick
  const double span = std::max(t1 - t0, 1e-3);
  const double x_step = nice_step(span, 5);
  const int x_ticks = std::max(1, static_cast<int>(std::ceil(span / x_step - 1e-9)));
  fig.range[0][0] = static_cast<float>(t0);
  fig.range[0][1] = static_cast<float>(t0 + x_ticks * x_step);
  fig.gridsize[0] = x_ticks + 1;

  // value axis from 0 to a round value above a high percentile (one spike must not flatten
  // the curves)
  std::vector<float> values;
  for (const auto& curve : curves_) {
    for (const auto& p : curve) {
      if (std::isfinite(p[1])) values.push_back(p[1]);
    }
  }
  double top = 1;
  if (!values.empty()) {
    std::sort(values.begin(), values.end());
    const double p = values[static_cast<std::size_t>(0.995 * static_cast<double>(values.size() - 1))];
    if (p > 0) top = 1.05 * p;
  }
  const double y_step = nice_step(top, 4);
  const int y_ticks = std::max(1, static_cast<int>(std::ceil(top / y_step - 1e-9)));
  fig.range[1][0] = 0;
  fig.range[1][1] = static_cast<float>(y_ticks * y_step);
  fig.gridsize[1] = y_ticks + 1;
}

void TimePlot::draw(const mjrRect& viewport, double t, const mjrContext& con) {
  mjvFigure& fig = *fig_;
  for (std::size_t i = 0; i < curves_.size(); ++i) {
    int n = 0;
    for (const auto& p : curves_[i]) {
      if (p[0] > t + 1e-9) break;
      fig.linedata[i][2 * n] = p[0];
      // points above the axis are clipped to it rather than drawn outside the plot
      fig.linedata[i][2 * n + 1] = std::isfinite(p[1]) ? std::min(p[1], fig.range[1][1]) : p[1];
      ++n;
    }
    fig.linepnt[i] = n;
  }
  fig.selection = static_cast<float>(t);
  mjr_figure(viewport, &fig, &con);
}

}  // namespace idmpc::render
