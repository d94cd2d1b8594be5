#include "idmpc/render/replay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace idmpc::render {
namespace {

constexpr long kMaxFrames = 1000000;  // ~9 h at 30 fps: anything more is a typo

std::string fmt(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

}  // namespace

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
    std::copy(replay.log->q_row(row), replay.log->q_row(row) + m->nq, d->qpos);
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
  // both ends shown: t0, t0 + step, ..., the last frame at or just before t_end
  const double count = std::floor((s.t_end - s.t0) / s.step + 1e-9) + 1;
  if (count > static_cast<double>(kMaxFrames)) {
    throw std::invalid_argument(
        "video length: expected at most " + std::to_string(kMaxFrames) + " frames, got " +
        fmt("%.0f", count) + " (a log of " + fmt("%g", s.t_end - s.t0) + " s at --fps " +
        fmt("%g", options.fps) + " and --speed " + fmt("%g", options.speed) + ")");
  }
  s.frames = static_cast<long>(count);
  return s;
}

}  // namespace idmpc::render
