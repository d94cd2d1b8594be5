#include "idmpc/render/close_up.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

namespace idmpc::render {
namespace {

bool overlaps(const mjrRect& a, const mjrRect& b) {
  if (a.width <= 0 || a.height <= 0 || b.width <= 0 || b.height <= 0) return false;
  return a.left < b.left + b.width && b.left < a.left + a.width && a.bottom < b.bottom + b.height &&
         b.bottom < a.bottom + a.height;
}

ScreenRegion ndc(const mjrRect& r, int width, int height) {
  return {2.0 * r.left / width - 1, 2.0 * (r.left + r.width) / width - 1, 2.0 * r.bottom / height - 1,
          2.0 * (r.bottom + r.height) / height - 1};
}

int even(double x) { return 2 * static_cast<int>(std::lround(x / 2)); }

}  // namespace

CloseUp plan_close_up(const FramePath& path, const Bounds& motion, double azimuth, double elevation,
                      double fovy_deg, int width, int height, const OverlayPlaces& places,
                      const ScreenMask& robot, int margin) {
  CloseUp out;
  if (path.empty() || motion.empty()) return out;
  Bounds box;
  const Vec3 half{path.marker_radius(), path.marker_radius(), path.marker_radius()};
  for (const Vec3& p : path.target_dots()) box.extend(p.data(), half);
  for (const Vec3& p : path.trail_points()) {
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) box.extend(p.data(), half);
  }
  if (box.empty() || !(box.size() < kCloseUpRatio * motion.size())) return out;
  // a margin of the tool around the path: the box 1.4 times as large about its centre
  const Vec3 c = box.center(), e = box.extent();
  box.extend(c.data(), Vec3{0.7 * e[0], 0.7 * e[1], 0.7 * e[2]});

  // a flat path (a circle) is seen square-on from the side away from the arm's motion, where
  // the tool does not hide it; any other with the main view's angles
  double view_azimuth = azimuth, view_elevation = elevation;
  const std::vector<Vec3>& dots = path.target_dots();
  if (dots.size() >= 3) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Vec3& p : dots) mean += Eigen::Vector3d(p[0], p[1], p[2]);
    mean /= static_cast<double>(dots.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Vec3& p : dots) {
      const Eigen::Vector3d d = Eigen::Vector3d(p[0], p[1], p[2]) - mean;
      cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(cov);
    const Eigen::Vector3d spread = pca.eigenvalues();  // increasing
    if (spread[1] > 0 && spread[0] <= 1e-6 * spread[2]) {
      Eigen::Vector3d n = pca.eigenvectors().col(0);
      const Vec3 mc = motion.center();
      if (n.dot(mean - Eigen::Vector3d(mc[0], mc[1], mc[2])) < 0) n = -n;
      // the camera on +n looks along −n, at most 75° up or down
      const Eigen::Vector3d forward = -n;
      view_azimuth = std::atan2(forward[1], forward[0]) * 180 / M_PI;
      view_elevation = std::clamp(std::asin(std::clamp(forward[2], -1.0, 1.0)) * 180 / M_PI, -75.0, 75.0);
    }
  }

  const int w = even(kCloseUpSide * width), h = even(kCloseUpSide * height);
  const std::array<mjrRect, 4> corners{mjrRect{width - margin - w, height - margin - h, w, h},
                                       mjrRect{margin, height - margin - h, w, h}, mjrRect{margin, margin, w, h},
                                       mjrRect{width - margin - w, margin, w, h}};
  for (const mjrRect& r : corners) {
    if (w < 16 || h < 16 || overlaps(r, places.table) || overlaps(r, places.plot)) continue;
    if (robot.count(ndc(r, width, height)) > 0) continue;
    // the path's box inside the close-up, a little in from its edges
    const FreeCamera fc = fit_camera(box, view_azimuth, view_elevation, fovy_deg, static_cast<double>(w) / h,
                                     ScreenRegion{-0.85, 0.85, -0.85, 0.85});
    if (!(fc.distance > 0)) return out;
    mjv_defaultCamera(&out.cam);
    out.cam.type = mjCAMERA_FREE;
    std::copy(fc.lookat.begin(), fc.lookat.end(), out.cam.lookat);
    out.cam.distance = fc.distance;
    out.cam.azimuth = fc.azimuth;
    out.cam.elevation = fc.elevation;
    out.rect = r;
    out.shown = true;
    return out;
  }
  return out;
}

void draw_close_up_border(const CloseUp& close_up) {
  if (!close_up.shown) return;
  const mjrRect& r = close_up.rect;
  const int t = std::max(1, r.height / 120);
  const float grey = 0.85f;
  mjr_rectangle(mjrRect{r.left - t, r.bottom - t, r.width + 2 * t, t}, grey, grey, grey, 1);
  mjr_rectangle(mjrRect{r.left - t, r.bottom + r.height, r.width + 2 * t, t}, grey, grey, grey, 1);
  mjr_rectangle(mjrRect{r.left - t, r.bottom, t, r.height}, grey, grey, grey, 1);
  mjr_rectangle(mjrRect{r.left + r.width, r.bottom, t, r.height}, grey, grey, grey, 1);
}

}  // namespace idmpc::render
