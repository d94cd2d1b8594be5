#include "idmpc/render/camera.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/render/scene_dressing.hpp"

namespace idmpc::render {
namespace {

constexpr double kPlanarTolerance = 0.02;  // thin extent / largest extent below this: planar
constexpr double kAutoElevation = -12;     // degrees: slightly above a planar arm
constexpr double kObliqueAzimuth = 60;     // degrees: spatial motion, seen from the front left
constexpr double kObliqueElevation = -20;
constexpr double kFrameMargin = 0.04;      // NDC kept free at the image border and around overlays
constexpr int kMaxMaskCell = 8;            // pixels per footprint cell side, at most...
constexpr int kMaskRows = 90;              // ...and at least this many cell rows
constexpr int kMaxPieces = 16;             // pieces a long geom is cut into for its footprint

bool geom_visible(const mjModel* m, const mjvOption& opt, int g) {
  const int group = m->geom_group[g];
  if (group >= 0 && group < mjNGROUP && !opt.geomgroup[group]) return false;
  const int mat = m->geom_matid[g];
  const float alpha = mat >= 0 ? m->mat_rgba[4 * mat + 3] : m->geom_rgba[4 * g + 3];
  return alpha > 0;
}

// world axis-aligned half-extents of a geom placed by d
Vec3 geom_half_extent(const mjModel* m, const mjData* d, int g) {
  const mjtNum* s = m->geom_size + 3 * g;
  Vec3 local;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE: local = {s[0], s[0], s[0]}; break;
    case mjGEOM_CAPSULE: local = {s[0], s[0], s[1] + s[0]}; break;
    case mjGEOM_CYLINDER: local = {s[0], s[0], s[1]}; break;
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID: local = {s[0], s[1], s[2]}; break;
    default: {
      const double r = m->geom_rbound[g];
      return {r, r, r};
    }
  }
  const mjtNum* R = d->geom_xmat + 9 * g;
  Vec3 half{0, 0, 0};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) half[i] += std::fabs(R[3 * i + j]) * local[j];
  }
  return half;
}

// MuJoCo's OpenGL view of a scene camera on a viewport of the given aspect (mjr_render's
// glFrustum and look-at): points to normalized device coordinates
struct GlView {
  Vec3 pos, fwd, up, right;
  double near = 0, center = 0, mid_y = 0, half_w = 1, half_h = 1;

  GlView(const mjvScene& scn, double aspect) {
    // the two eyes coincide without stereo: their mean
    const mjvGLCamera& a = scn.camera[0];
    const mjvGLCamera& b = scn.camera[1];
    for (std::size_t i = 0; i < 3; ++i) {
      pos[i] = 0.5 * (a.pos[i] + b.pos[i]);
      fwd[i] = 0.5 * (a.forward[i] + b.forward[i]);
      up[i] = 0.5 * (a.up[i] + b.up[i]);
    }
    right = {fwd[1] * up[2] - fwd[2] * up[1], fwd[2] * up[0] - fwd[0] * up[2],
             fwd[0] * up[1] - fwd[1] * up[0]};
    near = 0.5 * (a.frustum_near + b.frustum_near);
    center = 0.5 * (a.frustum_center + b.frustum_center);
    const double bottom = 0.5 * (a.frustum_bottom + b.frustum_bottom);
    const double top = 0.5 * (a.frustum_top + b.frustum_top);
    mid_y = 0.5 * (top + bottom);
    half_h = std::max(0.5 * (top - bottom), 1e-12);
    half_w = std::max(aspect * half_h, 1e-12);
  }

  // false for a point on or behind the near plane
  bool project(const Vec3& p, double& x, double& y) const {
    const Vec3 rel{p[0] - pos[0], p[1] - pos[1], p[2] - pos[2]};
    const double depth = rel[0] * fwd[0] + rel[1] * fwd[1] + rel[2] * fwd[2];
    if (!(depth > near)) return false;
    const double xe = rel[0] * right[0] + rel[1] * right[1] + rel[2] * right[2];
    const double ye = rel[0] * up[0] + rel[1] * up[1] + rel[2] * up[2];
    x = (near * xe / depth - center) / half_w;
    y = (near * ye / depth - mid_y) / half_h;
    return true;
  }
};

// half-sizes of a scene geom's box in its own frame
Vec3 scene_geom_half(const mjvGeom& g) {
  const double s0 = g.size[0], s1 = g.size[1], s2 = g.size[2];
  switch (g.type) {
    case mjGEOM_SPHERE: return {s0, s0, s0};
    case mjGEOM_CAPSULE: return {s0, s1, s2 + s0};
    case mjGEOM_CYLINDER:
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID: return {s0, s1, s2};
    default: {
      const double r = g.modelrbound > 0 ? g.modelrbound : std::max({s0, s1, s2});
      return {r, r, r};
    }
  }
}

// marks where a scene geom appears; false when part of it is behind the camera
bool mark_geom(ScreenMask& mask, const GlView& view, const mjvGeom& g) {
  // cut the box along its longest side into pieces about as long as it is thick
  const Vec3 half = scene_geom_half(g);
  const std::size_t k = static_cast<std::size_t>(std::max_element(half.begin(), half.end()) -
                                                  half.begin());
  double thick = 0;
  for (std::size_t j = 0; j < 3; ++j) {
    if (j != k) thick = std::max(thick, half[j]);
  }
  const int pieces = std::clamp(
      static_cast<int>(std::ceil(half[k] / std::max(thick, 1e-9 * half[k] + 1e-12))), 1,
      kMaxPieces);
  Vec3 piece = half;
  piece[k] = half[k] / pieces;
  // each piece: the screen box of its eight corners
  for (int p = 0; p < pieces; ++p) {
    Vec3 centre{0, 0, 0};
    centre[k] = -half[k] + (2 * p + 1) * piece[k];
    ScreenRegion box{1e300, -1e300, 1e300, -1e300};
    for (int c = 0; c < 8; ++c) {
      const Vec3 local{centre[0] + ((c & 1) ? piece[0] : -piece[0]),
                       centre[1] + ((c & 2) ? piece[1] : -piece[1]),
                       centre[2] + ((c & 4) ? piece[2] : -piece[2])};
      Vec3 world;
      for (std::size_t i = 0; i < 3; ++i) {
        world[i] = g.pos[i] + g.mat[3 * i] * local[0] + g.mat[3 * i + 1] * local[1] +
                   g.mat[3 * i + 2] * local[2];
      }
      double x = 0, y = 0;
      if (!view.project(world, x, y)) return false;
      box = {std::min(box.x_lo, x), std::max(box.x_hi, x), std::min(box.y_lo, y),
             std::max(box.y_hi, y)};
    }
    mask.mark(box);
  }
  return true;
}

}  // namespace

CameraSpec parse_camera(const std::string& text) {
  const std::string expected =
      "--camera: expected 'auto', 'fixed:<camera name>' or 'azimuth,elevation,distance' "
      "(degrees, degrees in [-90, 90], metres > 0), got '" + text + "'";
  CameraSpec spec;
  if (text == "auto") return spec;
  if (text.rfind("fixed:", 0) == 0) {
    spec.kind = CameraSpec::Kind::kFixed;
    spec.name = text.substr(6);
    if (spec.name.empty()) throw std::invalid_argument(expected);
    return spec;
  }
  std::vector<double> values;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v)) throw std::invalid_argument(expected);
    values.push_back(v);
  }
  if (values.size() != 3 || values[2] <= 0 || std::fabs(values[1]) > 90) {
    throw std::invalid_argument(expected);
  }
  spec.kind = CameraSpec::Kind::kOrbit;
  spec.azimuth = values[0];
  spec.elevation = values[1];
  spec.distance = values[2];
  return spec;
}

int find_fixed_camera(const mjModel* m, const CameraSpec& spec, const std::string& model_path) {
  if (spec.kind != CameraSpec::Kind::kFixed) return -1;
  const int id = mj_name2id(m, mjOBJ_CAMERA, spec.name.c_str());
  if (id >= 0) return id;
  std::string names;
  for (int c = 0; c < m->ncam; ++c) names += (c ? ", " : "") + mj::object_name(m, mjOBJ_CAMERA, c);
  throw std::invalid_argument("--camera: model '" + model_path + "' has no camera named '" +
                              spec.name + "'; expected one of: " +
                              (names.empty() ? std::string("(none)") : names));
}

Motion measure_motion(const mjModel* m, const std::vector<mjData*>& datas,
                      const std::vector<Replay>& replays, const Schedule& schedule,
                      const mjvOption& opt) {
  Motion motion;
  // every frame of every run: the visible geoms' boxes and the moving bodies' origins
  for (long k = 0; k < schedule.frames; ++k) {
    for (std::size_t r = 0; r < replays.size(); ++r) {
      mjData* d = datas[r];
      set_pose(m, d, replays[r], schedule.time(k));
      for (int g = 0; g < m->ngeom; ++g) {
        if (m->geom_type[g] == mjGEOM_PLANE || !geom_visible(m, opt, g)) continue;
        motion.visible.extend(d->geom_xpos + 3 * g, geom_half_extent(m, d, g));
      }
      for (int b = 1; b < m->nbody; ++b) {
        if (m->body_weldid[b] != 0) motion.bodies.extend(d->xpos + 3 * b, Vec3{0, 0, 0});
      }
    }
  }
  for (const Replay& r : replays) extend_by_frame_path(motion.visible, *r.log);
  // nothing visible: the model's own extent
  if (motion.visible.empty()) {
    const double e = m->stat.extent;
    motion.visible.extend(m->stat.center, Vec3{e, e, e});
  }
  return motion;
}

ScreenMask robot_footprint(const mjModel* m, const std::vector<mjData*>& datas,
                           const std::vector<Replay>& replays, const Schedule& schedule,
                           const mjvOption& opt, mjvCamera& cam, mjvScene& scn, int width,
                           int height, const std::vector<FramePath>& paths) {
  // cells finer than the margin the free camera keeps around the overlays
  const int cell = std::clamp(height / kMaskRows, 1, kMaxMaskCell);
  ScreenMask mask((width + cell - 1) / cell, (height + cell - 1) / cell);
  const double aspect = static_cast<double>(width) / height;
  // every frame of every run, as MuJoCo places the camera and the geoms
  for (long k = 0; k < schedule.frames; ++k) {
    for (std::size_t r = 0; r < replays.size(); ++r) {
      set_pose(m, datas[r], replays[r], schedule.time(k));
      mjv_updateScene(m, datas[r], &opt, nullptr, &cam, mjCAT_DYNAMIC, &scn);
      const GlView view(scn, aspect);
      for (int i = 0; i < scn.ngeom; ++i) {
        if (!moving_geom(m, scn.geoms[i])) continue;
        // a geom reaching behind the camera could be anywhere on the image
        if (!mark_geom(mask, view, scn.geoms[i])) {
          mask.mark_all();
          return mask;
        }
      }
      // the paths, as this frame's camera sees them
      if (r > 0) continue;
      for (const FramePath& path : paths) {
        for (const std::vector<Vec3>* points : {&path.target_dots(), &path.trail_points()}) {
          for (const Vec3& p : *points) {
            mjvGeom marker;
            const mjtNum size[3] = {path.marker_radius(), path.marker_radius(), path.marker_radius()};
            const mjtNum pos[3] = {p[0], p[1], p[2]};
            mjv_initGeom(&marker, mjGEOM_SPHERE, size, pos, nullptr, nullptr);
            if (!mark_geom(mask, view, marker)) {
              mask.mark_all();
              return mask;
            }
          }
        }
      }
    }
  }
  return mask;
}

std::vector<ScreenRegion> free_regions(const std::vector<ScreenRegion>& overlays) {
  std::vector<ScreenRegion> regions{
      {-1 + kFrameMargin, 1 - kFrameMargin, -1 + kFrameMargin, 1 - kFrameMargin}};
  for (const ScreenRegion& o : overlays) {
    std::vector<ScreenRegion> next;
    for (const ScreenRegion& r : regions) {
      // left or right of the overlay, whichever side has room
      ScreenRegion side = r;
      if (o.x_lo + o.x_hi < 0) {
        side.x_lo = std::max(side.x_lo, o.x_hi + kFrameMargin);
      } else {
        side.x_hi = std::min(side.x_hi, o.x_lo - kFrameMargin);
      }
      // above or below it
      ScreenRegion level = r;
      if (o.y_lo + o.y_hi > 0) {
        level.y_hi = std::min(level.y_hi, o.y_lo - kFrameMargin);
      } else {
        level.y_lo = std::max(level.y_lo, o.y_hi + kFrameMargin);
      }
      next.push_back(side);
      next.push_back(level);
    }
    regions.swap(next);
  }
  return regions;
}

mjvCamera make_camera(const mjModel* m, const CameraSpec& spec, int fixed_camid,
                      const Motion& motion, const std::vector<ScreenRegion>& regions,
                      double aspect, FreeCamera& free_cam) {
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  if (spec.kind == CameraSpec::Kind::kFixed) {
    cam.type = mjCAMERA_FIXED;
    cam.fixedcamid = fixed_camid;
    return cam;
  }
  // the angles: given, or square-on to a planar motion, or oblique
  double azimuth = kObliqueAzimuth;
  double elevation = kObliqueElevation;
  if (spec.kind == CameraSpec::Kind::kOrbit) {
    azimuth = spec.azimuth;
    elevation = spec.elevation;
  } else if (!motion.bodies.empty()) {
    const Vec3 e = motion.bodies.extent();
    const double largest = std::max({e[0], e[1], e[2], 1e-6});
    if (e[1] <= kPlanarTolerance * largest && e[1] <= e[0]) {
      azimuth = 90;  // motion in xz: look along +y
      elevation = kAutoElevation;
    } else if (e[0] <= kPlanarTolerance * largest) {
      azimuth = 0;  // motion in yz: look along +x
      elevation = kAutoElevation;
    }
  }
  // the closest camera whose view of the motion fits one free region
  const double fovy = m->vis.global.fovy;
  free_cam = fit_camera_best(motion.visible, azimuth, elevation, fovy, aspect, regions);
  if (free_cam.distance <= 0) {
    // the overlays leave no room (a tiny video): use the whole frame, let them overlap
    free_cam = fit_camera(motion.visible, azimuth, elevation, fovy, aspect,
                          ScreenRegion{-1 + kFrameMargin, 1 - kFrameMargin, -1 + kFrameMargin,
                                       1 - kFrameMargin});
  }
  if (spec.kind == CameraSpec::Kind::kOrbit) free_cam.distance = spec.distance;
  cam.type = mjCAMERA_FREE;
  std::copy(free_cam.lookat.begin(), free_cam.lookat.end(), cam.lookat);
  cam.distance = free_cam.distance;
  cam.azimuth = free_cam.azimuth;
  cam.elevation = free_cam.elevation;
  return cam;
}

}  // namespace idmpc::render
