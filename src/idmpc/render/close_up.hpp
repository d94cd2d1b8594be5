#pragma once
/// @file close_up.hpp
/// @brief A close-up of a frame target's path in a corner of the video: a tracking task's path
/// (a 5 cm circle beside a metre-long arm) is a few pixels wide in a view of the whole motion.

#include <mujoco/mujoco.h>

#include "idmpc/render/frame_path.hpp"
#include "idmpc/render/framing.hpp"
#include "idmpc/render/run_overlay.hpp"

namespace idmpc::render {

/// a path spanning less than this fraction of the motion's box gets a close-up
inline constexpr double kCloseUpRatio = 0.25;
/// the close-up's side, as a fraction of the video's
inline constexpr double kCloseUpSide = 0.3;

/// @brief Where the close-up goes and the camera it is seen with (shown = false: none).
struct CloseUp {
  bool shown = false;
  mjrRect rect{0, 0, 0, 0};  ///< pixels, from the bottom left
  mjvCamera cam{};           ///< a free camera
};

/// @brief The close-up of `path` (its target's dots and the trail over the whole run), or none:
/// when the path is empty or spans kCloseUpRatio of the motion's box or more, or when no corner
/// (top right, top left, bottom left, bottom right, in that order) of kCloseUpSide of the video
/// is clear of the overlays' places and of the robot's footprint. A flat path (a circle: its
/// target's dots in a plane) is seen square-on from the side of its plane away from the
/// motion's centre, where the tool does not hide it (at most 75° from the horizontal); any other
/// with the main view's angles. The path and a margin around it (its box 1.4 times as large)
/// fill the close-up.
CloseUp plan_close_up(const FramePath& path, const Bounds& motion, double azimuth, double elevation,
                      double fovy_deg, int width, int height, const OverlayPlaces& places,
                      const ScreenMask& robot, int margin);

/// @brief A thin light frame around the close-up (after it is rendered).
void draw_close_up_border(const CloseUp& close_up);

}  // namespace idmpc::render
