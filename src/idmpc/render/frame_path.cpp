#include "idmpc/render/frame_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace idmpc::render {
namespace {

constexpr double kTrailRadius = 0.003;  // of the motion's largest side
constexpr float kEmission = 0.35f;  // the paths stay bright on the shaded side
constexpr double kDotSpacing = 4;   // dot radii between the target path's dots
constexpr double kDotKeepOut = 0.75;  // a dot this close (in spacings) to another is left out

bool finite(const Vec3& p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

double distance(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

Vec3 row3(const std::vector<double>& values, std::size_t row) {
  const double* p = values.data() + 3 * row;
  return {p[0], p[1], p[2]};
}

// a decor geom at the end of the scene, or null when the scene is full
mjvGeom* new_geom(mjvScene& scn, int type, const mjtNum size[3], const mjtNum pos[3], const Rgb& rgb) {
  if (scn.ngeom >= scn.maxgeom) return nullptr;
  mjvGeom* g = scn.geoms + scn.ngeom++;
  const float rgba[4] = {rgb[0], rgb[1], rgb[2], 1};
  mjv_initGeom(g, type, size, pos, nullptr, rgba);
  g->category = mjCAT_DECOR;
  g->emission = kEmission;
  g->specular = 0.3f;
  return g;
}

void add_sphere(mjvScene& scn, const Vec3& p, double radius, const Rgb& rgb) {
  const mjtNum size[3] = {radius, radius, radius};
  const mjtNum pos[3] = {p[0], p[1], p[2]};
  new_geom(scn, mjGEOM_SPHERE, size, pos, rgb);
}

void add_capsule(mjvScene& scn, const Vec3& a, const Vec3& b, double radius, const Rgb& rgb) {
  if (!(distance(a, b) > 1e-9)) return;  // a connector needs a direction
  mjvGeom* g = new_geom(scn, mjGEOM_CAPSULE, nullptr, nullptr, rgb);
  if (g) mjv_makeConnector(g, mjGEOM_CAPSULE, radius, a[0], a[1], a[2], b[0], b[1], b[2]);
}

}  // namespace

double trail_radius(const Bounds& motion) { return kTrailRadius * std::max(motion.size(), 1e-3); }

bool has_frame_path(const RunLog& log) {
  return log.rows() > 0 && log.frame.size() == 3 * log.rows() && log.frame_ref.size() == 3 * log.rows();
}

double frame_error(const RunLog& log, std::size_t row) {
  if (!has_frame_path(log) || row >= log.rows()) return std::numeric_limits<double>::quiet_NaN();
  return distance(row3(log.frame, row), row3(log.frame_ref, row));
}

void extend_by_frame_path(Bounds& box, const RunLog& log) {
  if (!has_frame_path(log)) return;
  for (std::size_t i = 0; i < log.rows(); ++i) {
    for (const std::vector<double>* values : {&log.frame, &log.frame_ref}) {
      const Vec3 p = row3(*values, i);
      if (finite(p)) box.extend(p.data(), Vec3{0, 0, 0});
    }
  }
}

FramePath::FramePath(const RunLog& log, double radius) : radius_(radius) {
  if (!has_frame_path(log)) return;
  log_ = &log;
  const std::size_t rows = log.rows();

  // the runs of finite positions: the trail breaks between them
  run_start_.assign(rows, rows);
  for (std::size_t i = 0; i < rows; ++i) {
    if (!finite(position(i))) continue;
    run_start_[i] = (i > 0 && run_start_[i - 1] < rows) ? run_start_[i - 1] : i;
  }
  auto joined = [&](std::size_t i) { return i > 0 && run_start_[i] < rows && run_start_[i] == run_start_[i - 1]; };

  // the trail: each run's first point, then a vertex every length / kMaxPathSegments of arc
  double length = 0;
  for (std::size_t i = 1; i < rows; ++i) {
    if (joined(i)) length += distance(position(i - 1), position(i));
  }
  const double step = length / kMaxPathSegments;
  double since = 0;
  for (std::size_t i = 0; i < rows && trail_.size() <= static_cast<std::size_t>(kMaxPathSegments); ++i) {
    if (run_start_[i] >= rows) continue;
    if (joined(i)) {
      since += distance(position(i - 1), position(i));
      if (since < step || since == 0) continue;
    }
    since = 0;
    trail_.push_back(position(i));
    trail_rows_.push_back(i);
  }

  // the target's dots: one every `spacing` of its path, left out where an earlier dot is near
  // (the same path run again)
  double ref_length = 0;
  for (std::size_t i = 1; i < rows; ++i) {
    const double d = distance(target(i - 1), target(i));
    if (std::isfinite(d)) ref_length += d;
  }
  const double spacing = std::max(kDotSpacing * dot_radius(), ref_length / kMaxPathSegments);
  double along = 0;
  bool after_gap = true;
  for (std::size_t i = 0; i < rows && dots_.size() <= static_cast<std::size_t>(kMaxPathSegments); ++i) {
    const Vec3 p = target(i);
    if (!finite(p)) {
      after_gap = true;
      continue;
    }
    if (!after_gap) along += distance(target(i - 1), p);
    const bool candidate = after_gap || along >= spacing;
    after_gap = false;
    if (!candidate) continue;
    along = 0;
    const bool near = std::any_of(dots_.begin(), dots_.end(),
                                  [&](const Vec3& q) { return distance(p, q) < kDotKeepOut * spacing; });
    if (!near) dots_.push_back(p);
  }
}

int FramePath::max_geoms() const {
  if (empty()) return 0;
  // the dots, a segment ending at each trail vertex after the first plus the one to the
  // current point, and the marker
  return static_cast<int>(dots_.size() + trail_.size()) + 1;
}

Vec3 FramePath::position(std::size_t row) const { return row3(log_->frame, row); }
Vec3 FramePath::target(std::size_t row) const { return row3(log_->frame_ref, row); }

void FramePath::add(mjvScene& scn, std::size_t row, bool with_target, const Rgb& trail_rgb) const {
  if (empty()) return;
  const std::size_t rows = log_->rows();
  row = std::min(row, rows - 1);
  if (with_target) {
    for (const Vec3& p : dots_) add_sphere(scn, p, dot_radius(), kTargetPath);
  }
  // the trail's segments up to the row, then on to the row's own position
  std::size_t last = trail_.size();
  for (std::size_t k = 0; k < trail_.size() && trail_rows_[k] <= row; ++k) {
    if (k > 0 && run_start_[trail_rows_[k]] == run_start_[trail_rows_[k - 1]]) {
      add_capsule(scn, trail_[k - 1], trail_[k], radius_, trail_rgb);
    }
    last = k;
  }
  if (last < trail_.size() && run_start_[row] < rows && run_start_[row] == run_start_[trail_rows_[last]]) {
    add_capsule(scn, trail_[last], position(row), radius_, trail_rgb);
  }
  if (with_target && finite(target(row))) add_sphere(scn, target(row), marker_radius(), kTargetPath);
}

}  // namespace idmpc::render
