#include "idmpc/render/replay.hpp"

#include <algorithm>
#include <limits>

namespace idmpc::render {

Replay::Replay(const RunLog& run) : log(&run), bad_from(run.rows()) {
  // the first row whose pose is not finite
  for (std::size_t i = 0; i < run.rows(); ++i) {
    if (!run.finite_pose(i)) {
      bad_from = i;
      break;
    }
  }
}

std::size_t Replay::pose_row(double t) const {
  const std::size_t i = log->nearest_row(t);
  if (i < bad_from) return i;
  return bad_from == 0 ? log->rows() : bad_from - 1;
}

void set_pose(const mjModel* m, mjData* d, const Replay& replay, double t) {
  const std::size_t row = replay.pose_row(t);
  if (row < replay.log->rows()) {
    log_pose(*replay.log, row, m, d->qpos);
  } else {
    std::copy(m->qpos0, m->qpos0 + m->nq, d->qpos);
  }
  mj_fwdPosition(m, d);
}

Schedule make_schedule(const std::vector<Replay>& replays, const VideoOptions& options) {
  Schedule s;
  s.t0 = std::numeric_limits<double>::infinity();
  s.t_end = -std::numeric_limits<double>::infinity();
  for (const auto& r : replays) {
    s.t0 = std::min(s.t0, r.log->t.front());
    s.t_end = std::max(s.t_end, r.log->t.back());
  }
  s.step = options.speed / options.fps;
  s.frames = video_frame_count(s.t_end - s.t0, options);
  return s;
}

}  // namespace idmpc::render
