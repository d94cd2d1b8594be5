#pragma once
/// @file replay.hpp
/// @brief Replaying run logs in MuJoCo: the times of a video's frames and the pose each run
/// shows at a time.

#include <algorithm>
#include <cstddef>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/render/run_log.hpp"
#include "idmpc/render/video.hpp"

namespace idmpc::render {

/// @brief Which log row a run shows at a time: the nearest row, holding the last finite pose
/// after a divergence.
struct Replay {
  const RunLog* log = nullptr;
  std::size_t bad_from = 0;  ///< first row with a non-finite q (rows() if none)

  explicit Replay(const RunLog& run);
  /// @brief The row whose pose is shown at time t, or rows() when the log has no finite pose.
  std::size_t pose_row(double t) const;
  bool diverged() const { return bad_from < log->rows(); }
  double divergence_time() const { return log->t[bad_from]; }
};

/// @brief Sets d's qpos to the pose the run shows at time t (the model's qpos0 when the log has
/// no finite pose) and computes the positions (mj_fwdPosition).
void set_pose(const mjModel* m, mjData* d, const Replay& replay, double t);

/// @brief The frames: one every speed/fps log seconds, from the earliest start to the latest
/// end, both ends shown.
struct Schedule {
  double t0 = 0;
  double t_end = 0;
  long frames = 1;
  double step = 0;
  double time(long k) const { return std::min(t_end, t0 + static_cast<double>(k) * step); }
};

/// @brief The schedule of a video of these runs. Throws std::invalid_argument when it would
/// need more frames than the options allow.
Schedule make_schedule(const std::vector<Replay>& replays, const VideoOptions& options);

}  // namespace idmpc::render
