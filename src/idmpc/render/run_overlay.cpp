#include "idmpc/render/run_overlay.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "idmpc/render/frame_path.hpp"

namespace idmpc::render {
namespace {

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

// a colour swatch and its name (compare mode's legend)
Row legend_row(const std::string& name, const Rgb& rgb) {
  Row row;
  row.swatch = true;
  row.swatch_rgb = rgb;
  row.cells = {{name, rgb}};
  return row;
}

// single run: key / value rows, then the paths' legend
std::vector<Row> single_rows(const Replay& r, double t, double speed) {
  const std::size_t row = r.log->nearest_row(t);
  std::vector<Row> rows;
  rows.push_back({{{"time", kKey}, {time_text(t, speed)}}});
  rows.push_back({{{"controller", kKey}, {r.log->label}}});
  rows.push_back({{{"|u|", kKey}, {value_text("%.3f N m", r.log->u_norm(row))}}});
  rows.push_back({{{"residual", kKey}, {value_text("%.3e", r.log->residual[row])}}});
  rows.push_back({{{"update", kKey}, {value_text("%.3f ms", r.log->update_ms[row])}}});
  if (has_frame_path(*r.log)) {
    rows.push_back({{{"error", kKey}, {value_text("%.1f mm", 1e3 * frame_error(*r.log, row))}}});
  }
  const std::string why = status(r, t);
  if (!why.empty()) rows.push_back({{{"status", kKey}, {why, kAlert}}});
  // the paths' legend: their names in their colours
  if (has_frame_path(*r.log)) rows.push_back({{{"target path", kTargetPath}, {"tool path", kToolPath}}});
  return rows;
}

// compare: the time, then per run a legend line and a line of values (with the frame's error
// for a run with a frame path), then the target path's legend
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
    if (has_frame_path(*r.log)) {
      values.cells.push_back({"err " + value_text("%.1f", 1e3 * frame_error(*r.log, row)) + " mm", kWhite});
    }
    const std::string why = status(r, t);
    if (!why.empty()) values.cells.push_back({why, kAlert});
    rows.push_back(values);
  }
  // the trails have their runs' colours
  if (std::any_of(replays.begin(), replays.end(), [](const Replay& r) { return has_frame_path(*r.log); })) {
    rows.push_back(legend_row("target path", kTargetPath));
  }
  return rows;
}

// compare: the second run's curve dashed on top, like its arm's stripe on the first
std::vector<PlotCurve> u_curves(const std::vector<Replay>& replays,
                                const std::vector<Rgb>& colours, const Schedule& schedule,
                                int columns) {
  std::vector<PlotCurve> curves;
  for (std::size_t r = 0; r < replays.size(); ++r) {
    curves.push_back(
        {u_envelope(*replays[r].log, schedule.t0, schedule.t_end, columns), colours[r], r > 0});
  }
  return curves;
}

// the plot's size in pixels: about 30 % x 28 % of the frame, at least what its labels need
int plot_width(const mjrContext& con, int width) {
  return std::max(24 * con.charWidth[static_cast<unsigned char>('0')], width * 30 / 100);
}
int plot_height(const mjrContext& con, int height) {
  return std::max(8 * con.charHeight, height * 28 / 100);
}

// pixel rectangle -> normalized device coordinates
ScreenRegion to_ndc(const mjrRect& r, int width, int height) {
  return {2.0 * r.left / width - 1, 2.0 * (r.left + r.width) / width - 1,
          2.0 * r.bottom / height - 1, 2.0 * (r.bottom + r.height) / height - 1};
}

}  // namespace

std::vector<std::array<float, 2>> u_envelope(const RunLog& log, double t0, double t1,
                                             int columns) {
  std::vector<std::array<float, 2>> curve;
  if (log.rows() == 0 || columns < 1) return curve;
  // a zero-length time axis: one point
  if (!(t1 > t0)) {
    const double u = log.u_norm(log.nearest_row(t0));
    if (std::isfinite(u)) curve.push_back({static_cast<float>(t0), static_cast<float>(u)});
    return curve;
  }
  const double span = (t1 - t0) / columns;
  for (int c = 0; c < columns; ++c) {
    // the rows inside this column's time span (the last span includes t1)
    const double a = t0 + span * c;
    const double b = c + 1 == columns ? t1 : t0 + span * (c + 1);
    if (b < log.t.front() - 1e-9) continue;
    if (a > log.t.back() + 1e-9) break;
    const auto first = std::lower_bound(log.t.begin(), log.t.end(), a);
    const auto last = c + 1 == columns ? std::upper_bound(log.t.begin(), log.t.end(), b)
                                       : std::lower_bound(log.t.begin(), log.t.end(), b);
    auto i = static_cast<std::size_t>(first - log.t.begin());
    const auto end = static_cast<std::size_t>(last - log.t.begin());
    // their largest |u|, up to the first non-finite one; the nearest row's if there is none
    double peak = -1;
    bool finite = true;
    if (i == end) {
      peak = log.u_norm(log.nearest_row(0.5 * (a + b)));
      finite = std::isfinite(peak);
    }
    for (; i < end; ++i) {
      const double u = log.u_norm(i);
      if (!std::isfinite(u)) {
        finite = false;
        break;
      }
      peak = std::max(peak, u);
    }
    if (peak >= 0 && std::isfinite(peak)) {
      curve.push_back({static_cast<float>(0.5 * (a + b)), static_cast<float>(peak)});
    }
    // the curve ends where the log turns non-finite
    if (!finite) break;
  }
  return curve;
}

OverlayPlaces place_overlays(const OverlayPlaces& wanted, const std::array<int, 2>& min_plot,
                             const ScreenMask& robot, int width, int height, int margin) {
  // a w x h rectangle in a corner: 0 top left, 1 top right, 2 bottom left, 3 bottom right
  auto corner = [&](int c, int w, int h) {
    const int left = (c % 2 == 0) ? margin : width - margin - w;
    const int bottom = (c < 2) ? height - margin - h : margin;
    return mjrRect{left, bottom, w, h};
  };
  auto covered = [&](const mjrRect& r) { return robot.count(to_ndc(r, width, height)); };
  auto apart = [&](const mjrRect& a, const mjrRect& b) {
    return b.width == 0 || a.left + a.width + margin <= b.left ||
           b.left + b.width + margin <= a.left || a.bottom + a.height + margin <= b.bottom ||
           b.bottom + b.height + margin <= a.bottom;
  };
  OverlayPlaces places;

  // the table: the first corner clear of the robot, else the one covering least of it
  if (wanted.table.width > 0) {
    const mjrRect& t = wanted.table;
    int best = -1;
    for (const int c : {0, 1, 2, 3}) {
      const mjrRect r = corner(c, t.width, t.height);
      const int cells = covered(r);
      if (best < 0 || cells < best) {
        best = cells;
        places.table = r;
      }
      if (cells == 0) break;
    }
  }
  // the plot: the first corner clear of the robot and the table, shrinking if need be
  if (wanted.plot.width > 0) {
    const mjrRect& p = wanted.plot;
    for (const double scale : {1.0, 0.8, 0.65}) {
      const int w = std::min(p.width, std::max(min_plot[0], static_cast<int>(scale * p.width)));
      const int h =
          std::min(p.height, std::max(min_plot[1], static_cast<int>(scale * p.height)));
      for (const int c : {3, 2, 1, 0}) {
        const mjrRect r = corner(c, w, h);
        if (covered(r) == 0 && apart(r, places.table)) {
          places.plot = r;
          return places;
        }
      }
    }
  }
  return places;
}

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
      plot_("|u| [N m]", schedule.t0, schedule.t_end,
            u_curves(replays, colours, schedule,
                     std::min(kPlotMaxSamples, plot_width(con, options.width)))) {
  // the table top left, sized for its widest frame
  for (long k = 0; k < schedule.frames; ++k) table_.fit(rows_at(schedule.time(k)));
  margin_ = std::max(4, height_ / 80);
  const mjrRect table{margin_, height_ - margin_ - table_.height(), table_.width(),
                      table_.height()};
  // the plot bottom right
  const int plot_w = plot_width(con, width_);
  const int plot_h = plot_height(con, height_);
  const mjrRect plot{width_ - plot_w - margin_, margin_, plot_w, plot_h};
  min_plot_ = {20 * con.charWidth[static_cast<unsigned char>('0')], 7 * con.charHeight};
  // a small video keeps the table and drops the plot rather than stack them
  const bool show_plot = table_.height() + plot_h + 3 * margin_ <= height_ && plot_w <= width_ / 2;
  if (options.overlay) places_.table = table;
  if (options.overlay && show_plot) places_.plot = plot;
}

std::vector<ScreenRegion> RunOverlay::regions() const {
  std::vector<ScreenRegion> overlays;
  if (places_.table.width > 0) overlays.push_back(to_ndc(places_.table, width_, height_));
  if (places_.plot.width > 0) overlays.push_back(to_ndc(places_.plot, width_, height_));
  return overlays;
}

void RunOverlay::avoid(const ScreenMask& robot) {
  places_ = place_overlays(places_, min_plot_, robot, width_, height_, margin_);
}

void RunOverlay::draw(double t) {
  const mjrRect& table = places_.table;
  if (table.width > 0) table_.draw(rows_at(t), table.left, table.bottom + table.height);
  if (places_.plot.width > 0) plot_.draw(places_.plot, t, con_);
}

std::vector<Row> RunOverlay::rows_at(double t) const {
  return replays_.size() == 2 ? compare_rows(replays_, colours_, t, speed_)
                              : single_rows(replays_[0], t, speed_);
}

}  // namespace idmpc::render
