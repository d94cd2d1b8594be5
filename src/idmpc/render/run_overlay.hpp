#pragma once
/// @file run_overlay.hpp
/// @brief The overlays over a video of runs: a table of the time and each run's label, |u|,
/// residual, update time, the frame's position error (runs with a frame target) and status,
/// with a legend of the frame paths' colours, and a plot of |u| over time.

#include <array>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/render/framing.hpp"
#include "idmpc/render/overlay.hpp"
#include "idmpc/render/replay.hpp"
#include "idmpc/render/video.hpp"

namespace idmpc::render {

/// single run: the |u| curve in a neutral colour (the arm keeps its own colours)
inline constexpr Rgb kSinglePlot = {0.92f, 0.92f, 0.92f};

/// @brief |u| of a run for a plot whose time axis [t0, t1] spans `columns` pixels: per column
/// the largest |u| of the log rows inside its time span (the nearest row's when none is),
/// placed at the span's middle, so a peak shorter than a pixel still shows at its full height.
/// The curve leaves out columns before the log starts and stops where the log ends or |u|
/// turns non-finite.
std::vector<std::array<float, 2>> u_envelope(const RunLog& log, double t0, double t1,
                                             int columns);

/// @brief Where the overlays go: pixel rectangles from the bottom left; width 0 = not shown.
struct OverlayPlaces {
  mjrRect table{0, 0, 0, 0};
  mjrRect plot{0, 0, 0, 0};
};

/// @brief Moves the overlays off the robot.
///
/// Each overlay goes to the first place, in order of preference, whose rectangle touches no
/// marked cell of `robot`: the table to a corner (top left, top right,
/// bottom left, bottom right), then the plot, clear of the table, to a corner (bottom right,
/// bottom left, top right, top left) at its size, then at 80 % and 65 % of it (not below
/// `min_plot`, width x height). A plot with no free place is dropped; a table with none goes to
/// the corner where it covers the least of the robot.
/// @param wanted the preferred places and full sizes (width 0: not shown)
/// @param width, height the frame in pixels; margin the gap kept to the border and between
/// the overlays
OverlayPlaces place_overlays(const OverlayPlaces& wanted, const std::array<int, 2>& min_plot,
                             const ScreenMask& robot, int width, int height, int margin);

/// @brief MuJoCo font scale for a video height (MuJoCo 2.2 renders mjFONTSCALE_50 as 100:
/// 100 is the smallest).
int font_scale_for(int height);

/// @brief The table and the |u| plot of one run (or two in compare mode, with a colour legend),
/// sized for the widest frame so the panels keep still: the table top left, the plot bottom
/// right, dropped on a video too small to hold both; avoid() moves them off the robot.
class RunOverlay {
 public:
  /// @param replays the runs, in the order of `colours` (kept by reference)
  /// @param colours one per run: its legend swatch and plot curve colour
  /// @param con MuJoCo's render context (fonts), kept by reference
  RunOverlay(const std::vector<Replay>& replays, const std::vector<Rgb>& colours,
             const Schedule& schedule, const VideoOptions& options, const mjrContext& con);

  /// @brief The rectangles the shown overlays cover, in normalized device coordinates.
  std::vector<ScreenRegion> regions() const;

  /// @brief Moves the overlays off the robot's footprint (place_overlays).
  void avoid(const ScreenMask& robot);

  /// @brief Where the overlays are.
  const OverlayPlaces& places() const { return places_; }

  /// @brief Draws the shown overlays for time t over the current framebuffer.
  void draw(double t);

 private:
  std::vector<Row> rows_at(double t) const;

  const std::vector<Replay>& replays_;
  std::vector<Rgb> colours_;
  double speed_ = 1;
  int width_ = 0, height_ = 0;
  const mjrContext& con_;
  TableLayout table_;
  TimePlot plot_;
  OverlayPlaces places_;
  std::array<int, 2> min_plot_{0, 0};
  int margin_ = 0;
};

}  // namespace idmpc::render
