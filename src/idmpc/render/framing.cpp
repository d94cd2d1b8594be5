#include "idmpc/render/framing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace idmpc::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// the box's corners projected to normalized device coordinates
struct Projection {
  double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;
  bool in_front = true;
};

struct View {
  Vec3 fwd, up, right;
  double tan_x, tan_y;

  Projection project(const Bounds& b, const Vec3& lookat, double distance) const {
    Projection p;
    p.x_lo = p.y_lo = std::numeric_limits<double>::infinity();
    p.x_hi = p.y_hi = -std::numeric_limits<double>::infinity();
    const Vec3 eye = sub(lookat, scale(fwd, distance));
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner{(c & 1) ? b.hi[0] : b.lo[0], (c & 2) ? b.hi[1] : b.lo[1],
                        (c & 4) ? b.hi[2] : b.lo[2]};
      const Vec3 rel = sub(corner, eye);
      const double z = dot(rel, fwd);
      if (z <= 1e-9 * distance) {
        p.in_front = false;
        return p;
      }
      const double x = dot(rel, right) / (z * tan_x);
      const double y = dot(rel, up) / (z * tan_y);
      p.x_lo = std::min(p.x_lo, x);
      p.x_hi = std::max(p.x_hi, x);
      p.y_lo = std::min(p.y_lo, y);
      p.y_hi = std::max(p.y_hi, y);
    }
    return p;
  }
};

}  // namespace

void Bounds::extend(const double* p, const Vec3& half) {
  for (std::size_t i = 0; i < 3; ++i) {
    lo[i] = std::min(lo[i], p[i] - half[i]);
    hi[i] = std::max(hi[i], p[i] + half[i]);
  }
}

Vec3 Bounds::center() const { return scale(add(lo, hi), 0.5); }
Vec3 Bounds::extent() const { return sub(hi, lo); }
double Bounds::size() const {
  const Vec3 e = extent();
  return std::max({e[0], e[1], e[2]});
}

ScreenMask::ScreenMask(int columns, int rows)
    : columns_(std::max(columns, 1)),
      rows_(std::max(rows, 1)),
      cells_(static_cast<std::size_t>(columns_) * static_cast<std::size_t>(rows_), 0) {}

bool ScreenMask::cell_range(const ScreenRegion& r, int& c0, int& c1, int& r0, int& r1) const {
  if (!(r.x_lo < 1 && r.x_hi > -1 && r.y_lo < 1 && r.y_hi > -1)) return false;
  // [-1, 1] -> cells; a region touches every cell it overlaps with positive area (a point
  // region touches the cell it is in)
  auto range = [](double lo, double hi, int cells, int& first, int& end) {
    first = std::clamp(static_cast<int>(std::floor(0.5 * (lo + 1) * cells)), 0, cells - 1);
    end = std::clamp(static_cast<int>(std::ceil(0.5 * (hi + 1) * cells)), first + 1, cells);
  };
  range(r.x_lo, r.x_hi, columns_, c0, c1);
  range(r.y_lo, r.y_hi, rows_, r0, r1);
  return true;
}

void ScreenMask::mark(const ScreenRegion& r) {
  int c0, c1, r0, r1;
  if (!cell_range(r, c0, c1, r0, r1)) return;
  for (int y = r0; y < r1; ++y) {
    std::fill_n(cells_.begin() + static_cast<std::ptrdiff_t>(y) * columns_ + c0, c1 - c0, 1);
  }
}

void ScreenMask::mark_all() { std::fill(cells_.begin(), cells_.end(), 1); }

int ScreenMask::count(const ScreenRegion& r) const {
  int c0, c1, r0, r1;
  if (!cell_range(r, c0, c1, r0, r1)) return 0;
  int n = 0;
  for (int y = r0; y < r1; ++y) {
    for (int x = c0; x < c1; ++x) n += cells_[static_cast<std::size_t>(y * columns_ + x)];
  }
  return n;
}

int ScreenMask::count() const {
  return static_cast<int>(std::count(cells_.begin(), cells_.end(), 1));
}

void camera_axes(double azimuth, double elevation, Vec3& forward, Vec3& up, Vec3& right) {
  const double ca = azimuth * kPi / 180;
  const double ce = elevation * kPi / 180;
  forward = {std::cos(ce) * std::cos(ca), std::cos(ce) * std::sin(ca), std::sin(ce)};
  up = {-std::sin(ce) * std::cos(ca), -std::sin(ce) * std::sin(ca), std::cos(ce)};
  right = cross(forward, up);
}

FreeCamera fit_camera(const Bounds& box, double azimuth, double elevation, double fovy_deg,
                      double aspect, const ScreenRegion& region) {
  FreeCamera cam;
  cam.azimuth = azimuth;
  cam.elevation = elevation;
  cam.lookat = box.center();
  if (region.width() <= 0 || region.height() <= 0) {
    cam.distance = -1;
    return cam;
  }
  View view;
  camera_axes(azimuth, elevation, view.fwd, view.up, view.right);
  view.tan_y = std::tan(0.5 * fovy_deg * kPi / 180);
  view.tan_x = view.tan_y * aspect;
  const double size = std::max(box.size(), 1e-3);
  const double cx = 0.5 * (region.x_lo + region.x_hi);
  const double cy = 0.5 * (region.y_lo + region.y_hi);

  // the projected size barely depends on where the camera aims: fit the size first
  auto size_fits = [&](double d) {
    const Projection p = view.project(box, cam.lookat, d);
    return p.in_front && p.x_hi - p.x_lo <= region.width() && p.y_hi - p.y_lo <= region.height();
  };
  // then move the aim so the projected box is centred in the region
  auto recentre = [&] {
    const Projection p = view.project(box, cam.lookat, cam.distance);
    if (!p.in_front) return;
    const double dx = (0.5 * (p.x_lo + p.x_hi) - cx) * cam.distance * view.tan_x;
    const double dy = (0.5 * (p.y_lo + p.y_hi) - cy) * cam.distance * view.tan_y;
    cam.lookat = add(cam.lookat, add(scale(view.right, dx), scale(view.up, dy)));
  };
  auto inside = [&] {
    const Projection p = view.project(box, cam.lookat, cam.distance);
    return p.in_front && p.x_lo >= region.x_lo - 1e-9 && p.x_hi <= region.x_hi + 1e-9 &&
           p.y_lo >= region.y_lo - 1e-9 && p.y_hi <= region.y_hi + 1e-9;
  };

  for (int pass = 0; pass < 4; ++pass) {
    double lo = 1e-3 * size;
    double hi = 1e4 * size;
    for (int it = 0; it < 100; ++it) {
      const double mid = std::sqrt(lo * hi);
      (size_fits(mid) ? hi : lo) = mid;
    }
    cam.distance = hi;
    for (int k = 0; k < 3; ++k) recentre();
  }
  // perspective leaves the box a little off: back off until it is inside
  for (int it = 0; it < 200 && !inside(); ++it) {
    cam.distance *= 1.005;
    recentre();
  }
  return cam;
}

FreeCamera fit_camera_best(const Bounds& box, double azimuth, double elevation, double fovy_deg,
                           double aspect, const std::vector<ScreenRegion>& regions) {
  FreeCamera best;
  best.distance = -1;
  for (const ScreenRegion& region : regions) {
    const FreeCamera cam = fit_camera(box, azimuth, elevation, fovy_deg, aspect, region);
    if (cam.distance > 0 && (best.distance < 0 || cam.distance < best.distance)) best = cam;
  }
  return best;
}

}  // namespace idmpc::render
