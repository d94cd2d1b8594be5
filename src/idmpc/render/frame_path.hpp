#pragma once
/// @file frame_path.hpp
/// @brief The paths of a run with a frame target (a log with the x..z_ref columns), drawn into
/// the scene: the target's path over the whole run as a chain of dots, the frame's travelled
/// path up to the current time as a thin trail, and the current target as a larger marker.

#include <cstddef>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/render/framing.hpp"
#include "idmpc/render/overlay.hpp"
#include "idmpc/render/run_log.hpp"

namespace idmpc::render {

/// the target's path and the current target: magenta
inline constexpr Rgb kTargetPath = {0.95f, 0.20f, 0.80f};
/// the frame's travelled path (single run; in compare mode each run's trail has its run's colour)
inline constexpr Rgb kToolPath = {0.20f, 0.92f, 0.35f};

/// most segments of a trail, and most dots of a target path (one more than this)
inline constexpr int kMaxPathSegments = 300;

/// @brief The trail's radius for a motion of this size: thin beside the arm, a few pixels wide
/// when the camera frames the whole motion.
double trail_radius(const Bounds& motion);

/// @brief Whether the log has a frame's position and target (RunLog::frame, frame_ref).
bool has_frame_path(const RunLog& log);

/// @brief The frame's position error |p − p_ref| [m] at a row, NaN when either is not finite or
/// the log has no frame columns.
double frame_error(const RunLog& log, std::size_t row);

/// @brief Grows the box to contain every finite position and target of the log's frame.
void extend_by_frame_path(Bounds& box, const RunLog& log);

/// @brief A run's paths, subsampled once for the whole video: the target's path as dots at
/// least about four dot radii apart (a target that repeats itself, e.g. a circle run several
/// times, keeps one chain of dots), and the trail's vertices by arc length. A log without frame
/// columns has no paths and adds nothing.
class FramePath {
 public:
  /// @param radius the trail's radius [m]; the target's dots have twice, the marker three
  /// times this radius
  FramePath(const RunLog& log, double radius);

  bool empty() const { return log_ == nullptr; }
  double radius() const { return radius_; }
  double dot_radius() const { return 2 * radius_; }
  double marker_radius() const { return 3 * radius_; }
  /// @brief The target path's dots (at most kMaxPathSegments + 1).
  const std::vector<Vec3>& target_dots() const { return dots_; }
  /// @brief The trail's vertices (at most kMaxPathSegments + 1) at their rows.
  const std::vector<Vec3>& trail_points() const { return trail_; }
  /// @brief The most geoms add() appends: the dots, the trail's segments and the marker.
  int max_geoms() const;

  /// @brief Appends to the scene, as decor geoms, the trail (in `trail_rgb`) up to log row
  /// `row` and, with `target`, the target's dots and its marker at `row`; stops when the scene
  /// is full. Points that are not finite break the trail and are not drawn.
  void add(mjvScene& scn, std::size_t row, bool target, const Rgb& trail_rgb) const;

 private:
  Vec3 position(std::size_t row) const;
  Vec3 target(std::size_t row) const;

  const RunLog* log_ = nullptr;
  double radius_ = 0;
  std::vector<Vec3> dots_;
  std::vector<Vec3> trail_;
  std::vector<std::size_t> trail_rows_;
  /// per row: the first row of the run of finite positions it belongs to (rows() if not finite)
  std::vector<std::size_t> run_start_;
};

}  // namespace idmpc::render
