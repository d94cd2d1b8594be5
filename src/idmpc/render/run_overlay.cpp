#include "idmpc/render/run_overlay.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace idmpc::render {
namespace {

constexpr int kPlotSamples = 800;  // |u| samples per run in the plot (<= mjMAXLINEPNT)
constexpr Rgb kKey = {0.70f, 0.70f, 0.70f};
constexpr Rgb kWhite = {1, 1, 1};
constexpr Rgb kAlert = {1.00f, 0.40f, 0.30f};

std::string fmt(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string value_text(const char* format, double v) {
  if (std::isfinite(v)) return fmt(format, v);
  return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
}

std::string time_text(double t, double speed) {
  std::string s = fmt("%.3f s", t);
  if (std::fabs(speed - 1) > 1e-9) s += "  (" + fmt("%g", speed) + "x speed)";
  return s;
}

// "" while the run is going, else why it stopped
std::string status(const Replay& r, double t) {
  if (r.diverged() && t >= r.divergence_time()) {
    return "diverged at " + fmt("%.3f s", r.divergence_time());
  }
  if (t > r.log->t.back() + 1e-9) return "ended at " + fmt("%.3f s", r.log->t.back());
  return "";
}

// single run: key / value rows
std::vector<Row> single_rows(const Replay& r, double t, double speed) {
  const std::size_t row = r.log->nearest_row(t);
  std::vector<Row> rows;
  rows.push_back({{{"time", kKey}, {time_text(t, speed)}}});
  rows.push_back({{{"controller", kKey}, {r.log->label}}});
  rows.push_back({{{"|u|", kKey}, {value_text("%.3f N m", r.log->u_norm(row))}}});
  rows.push_back({{{"residual", kKey}, {value_text("%.3e", r.log->residual[row])}}});
  rows.push_back({{{"update", kKey}, {value_text("%.3f ms", r.log->update_ms[row])}}});
  const std::string why = status(r, t);
  if (!why.empty()) rows.push_back({{{"status", kKey}, {why, kAlert}}});
  return rows;
}

// compare: the time, then per run a legend line and a line of values
std::vector<Row> compare_rows(const std::vector<Replay>& replays, const std::vector<Rgb>& colours,
                              double t, double speed) {
  std::vector<Row> rows;
  rows.push_back({{{"time  " + time_text(t, speed), kWhite}}});
  for (std::size_t i = 0; i < replays.size(); ++i) {
    const Replay& r = replays[i];
    const std::size_t row = r.log->nearest_row(t);
    Row legend;
    legend.swatch = true;
    legend.swatch_rgb = colours[i];
    legend.cells = {{r.log->label, colours[i]}};
    rows.push_back(legend);
    Row values;
    values.cells = {{"|u| " + value_text("%.3f", r.log->u_norm(row)), kWhite},
                    {"res " + value_text("%.2e", r.log->residual[row]), kWhite},
                    {value_text("%.3f", r.log->update_ms[row]) + " ms", kWhite}};
    const std::string why = status(r, t);
    if (!why.empty()) values.cells.push_back({why, kAlert});
    rows.push_back(values);
  }
  return rows;
}

// |u| over time until the log ends or turns non-finite
std::vector<std::array<float, 2>> u_curve(const Replay& r, const Schedule& s) {
  std::vector<std::array<float, 2>> curve;
  for (int i = 0; i < kPlotSamples; ++i) {
    const double t = s.t0 + (s.t_end - s.t0) * i / (kPlotSamples - 1);
    if (t < r.log->t.front() - 1e-9) continue;
    if (t > r.log->t.back() + 1e-9) break;
    const double u = r.log->u_norm(r.log->nearest_row(t));
    if (!std::isfinite(u)) break;
    curve.push_back({static_cast<float>(t), static_cast<float>(u)});
  }
  return curve;
}

// compare: the second run's curve dashed on top, like its arm's stripe on the first
std::vector<PlotCurve> u_curves(const std::vector<Replay>& replays,
                                const std::vector<Rgb>& colours, const Schedule& schedule) {
  std::vector<PlotCurve> curves;
  for (std::size_t r = 0; r < replays.size(); ++r) {
    curves.push_back({u_curve(replays[r], schedule), colours[r], r > 0});
  }
  return curves;
}

// pixel rectangle -> normalized device coordinates
ScreenRegion to_ndc(const mjrRect& r, int width, int height) {
  return {2.0 * r.left / width - 1, 2.0 * (r.left + r.width) / width - 1,
          2.0 * r.bottom / height - 1, 2.0 * (r.bottom + r.height) / height - 1};
}

}  // namespace

int font_scale_for(int height) {
  if (height < 600) return mjFONTSCALE_100;
  if (height < 1000) return mjFONTSCALE_150;
  return mjFONTSCALE_200;
}

RunOverlay::RunOverlay(const std::vector<Replay>& replays, const std::vector<Rgb>& colours,
                       const Schedule& schedule, const VideoOptions& options,
                       const mjrContext& con)
    : replays_(replays),
      colours_(colours),
      speed_(options.speed),
      width_(options.width),
      height_(options.height),
      con_(con),
      table_(con),
      plot_("|u| [N m]", schedule.t0, schedule.t_end, u_curves(replays, colours, schedule)) {
  // the table top left, sized for its widest frame
  for (long k = 0; k < schedule.frames; ++k) table_.fit(rows_at(schedule.time(k)));
  const int margin = std::max(4, height_ / 80);
  table_rect_ = {margin, height_ - margin - table_.height(), table_.width(), table_.height()};
  // the plot bottom right
  const int plot_w = std::max(24 * con.charWidth[static_cast<unsigned char>('0')],
                              width_ * 30 / 100);
  const int plot_h = std::max(8 * con.charHeight, height_ * 28 / 100);
  plot_rect_ = {width_ - plot_w - margin, margin, plot_w, plot_h};
  // a small video keeps the table and drops the plot rather than stack them
  show_table_ = options.overlay;
  show_plot_ = options.overlay && table_.height() + plot_h + 3 * margin <= height_ &&
               plot_w <= width_ / 2;
}

std::vector<ScreenRegion> RunOverlay::regions() const {
  std::vector<ScreenRegion> overlays;
  if (show_table_) overlays.push_back(to_ndc(table_rect_, width_, height_));
  if (show_plot_) overlays.push_back(to_ndc(plot_rect_, width_, height_));
  return overlays;
}

void RunOverlay::draw(double t) {
  if (show_table_) {
    table_.draw(rows_at(t), table_rect_.left, table_rect_.bottom + table_rect_.height);
  }
  if (show_plot_) plot_.draw(plot_rect_, t, con_);
}

std::vector<Row> RunOverlay::rows_at(double t) const {
  return replays_.size() == 2 ? compare_rows(replays_, colours_, t, speed_)
                              : single_rows(replays_[0], t, speed_);
}

}  // namespace idmpc::render
