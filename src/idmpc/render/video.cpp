#include "idmpc/render/video.hpp"

#include <GL/gl.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/render/framing.hpp"
#include "idmpc/render/gl_context.hpp"
#include "idmpc/render/overlay.hpp"
#include "idmpc/render/video_writer.hpp"

namespace idmpc::render {
namespace {

constexpr int kMaxSize = 8192;             // pixels per side
constexpr double kMaxFps = 240;
constexpr double kMaxSpeed = 1000;
constexpr long kMaxFrames = 1000000;       // ~9 h at 30 fps: anything more is a typo
constexpr double kPlanarTolerance = 0.02;  // thin extent / largest extent below this: planar
constexpr double kAutoElevation = -12;     // degrees: slightly above a planar arm
constexpr double kObliqueAzimuth = 60;     // degrees: spatial motion, seen from the front left
constexpr double kObliqueElevation = -20;
constexpr double kFrameMargin = 0.04;      // NDC kept free at the image border and around overlays
constexpr int kPlotSamples = 800;          // |u| samples per run in the plot (<= mjMAXLINEPNT)

// compare mode: the FD run solid blue; the ID run a thinner solid orange core drawn just in
// front of it (pulled towards the camera), so identical motion shows a blue arm with an
// orange stripe along it and any difference shows two arms
constexpr Rgb kBlue = {0.18f, 0.48f, 1.00f};
constexpr Rgb kOrange = {1.00f, 0.52f, 0.08f};
constexpr float kCoreScale = 0.45f;  // the core's cross-section relative to the arm's
constexpr Rgb kSinglePlot = {0.92f, 0.92f, 0.92f};  // neutral: the arm keeps its own colours
constexpr Rgb kKey = {0.70f, 0.70f, 0.70f};
constexpr Rgb kWhite = {1, 1, 1};
constexpr Rgb kAlert = {1.00f, 0.40f, 0.30f};

// sky gradient drawn behind the scene when the model has no skybox
constexpr Rgb kSkyTop = {0.11f, 0.13f, 0.17f};
constexpr Rgb kSkyHorizon = {0.42f, 0.47f, 0.54f};

Vec3 vsub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double vdot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

std::string fmt(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string value_text(const char* format, double v) {
  if (std::isfinite(v)) return fmt(format, v);
  return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
}

// ------------------------------------------------------------------------------- options

struct CameraSpec {
  enum class Kind { kAuto, kFixed, kOrbit } kind = Kind::kAuto;
  std::string name;                                 // kFixed
  double azimuth = 0, elevation = 0, distance = 0;  // kOrbit
};

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

// id of the model camera a "fixed:<name>" spec names (-1 for other specs)
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

// ------------------------------------------------------------------------------- RAII wrappers

struct Scene {
  mjvScene scn;
  Scene(const mjModel* m, int maxgeom) {
    mjv_defaultScene(&scn);
    mjv_makeScene(m, &scn, maxgeom);
  }
  ~Scene() { mjv_freeScene(&scn); }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
};

struct RenderContext {
  mjrContext con;
  RenderContext(const mjModel* m, int fontscale) {
    mjr_defaultContext(&con);
    try {
      mjr_makeContext(m, &con, fontscale);
    } catch (const std::exception& e) {
      mjr_freeContext(&con);
      throw std::runtime_error(
          std::string("MuJoCo could not set up OpenGL on the OSMesa context (mjr_makeContext): ") +
          e.what());
    }
    if (!con.offFBO) {
      mjr_freeContext(&con);
      throw std::runtime_error("MuJoCo's off-screen framebuffer: expected a framebuffer object, "
                               "got none (OpenGL without framebuffer objects?)");
    }
  }
  ~RenderContext() { mjr_freeContext(&con); }
  RenderContext(const RenderContext&) = delete;
  RenderContext& operator=(const RenderContext&) = delete;
};

// ------------------------------------------------------------------------------- replay

// which log row a run shows at a time; holds the last finite pose after a divergence
struct Replay {
  const RunLog* log = nullptr;
  std::size_t bad_from = 0;  // first row with a non-finite q (rows() if none)

  explicit Replay(const RunLog& run) : log(&run), bad_from(run.rows()) {
    for (std::size_t i = 0; i < run.rows(); ++i) {
      if (!run.finite_pose(i)) {
        bad_from = i;
        break;
      }
    }
  }
  // the row whose pose is shown at time t, or rows() when the log has no finite pose at all
  std::size_t pose_row(double t) const {
    const std::size_t i = log->nearest_row(t);
    if (i < bad_from) return i;
    return bad_from == 0 ? log->rows() : bad_from - 1;
  }
  bool diverged() const { return bad_from < log->rows(); }
  double divergence_time() const { return log->t[bad_from]; }

  // "" while the run is going, else why it stopped
  std::string status(double t) const {
    if (diverged() && t >= divergence_time()) {
      return "diverged at " + fmt("%.3f s", divergence_time());
    }
    if (t > log->t.back() + 1e-9) return "ended at " + fmt("%.3f s", log->t.back());
    return "";
  }
};

void set_pose(const mjModel* m, mjData* d, const Replay& replay, double t) {
  const std::size_t row = replay.pose_row(t);
  if (row < replay.log->rows()) {
    std::copy(replay.log->q_row(row), replay.log->q_row(row) + m->nq, d->qpos);
  } else {
    std::copy(m->qpos0, m->qpos0 + m->nq, d->qpos);
  }
  mj_fwdPosition(m, d);
}

// the frames: one every speed/fps log seconds, from the earliest start to the latest end
struct Schedule {
  double t0 = 0;
  double t_end = 0;
  long frames = 1;
  double step = 0;
  double time(long k) const { return std::min(t_end, t0 + static_cast<double>(k) * step); }
};

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

// ------------------------------------------------------------------------------- motion bounds

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

struct Motion {
  Bounds visible;  // every visible geom (moving and static) over all frames
  Bounds bodies;   // origins of the moving bodies: tells a planar motion
};

Motion measure_motion(const mjModel* m, const std::vector<mjData*>& datas,
                      const std::vector<Replay>& replays, const Schedule& schedule,
                      const mjvOption& opt) {
  Motion motion;
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
  if (motion.visible.empty()) {
    const double e = m->stat.extent;
    motion.visible.extend(m->stat.center, Vec3{e, e, e});
  }
  return motion;
}

// ------------------------------------------------------------------------------- scene dressing

bool has_plane(const mjModel* m) {
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] == mjGEOM_PLANE) return true;
  }
  return false;
}

bool has_skybox(const mjModel* m) {
  for (int t = 0; t < m->ntex; ++t) {
    if (m->tex_type[t] == mjTEXTURE_SKYBOX) return true;
  }
  return false;
}

// a checkered floor below the motion, for models without a ground plane
void add_floor(mjvScene& scn, const Bounds& motion) {
  const Vec3 c = motion.center();
  const double tile = nice_step(1.8 * motion.size() + 1, 14);
  const int half_tiles = static_cast<int>(std::ceil((0.9 * motion.size() + 0.5) / tile));
  const double z = std::min(0.0, motion.lo[2] - 0.02 * motion.size());
  const double x0 = std::round(c[0] / tile) * tile;
  const double y0 = std::round(c[1] / tile) * tile;
  const float dark[4] = {0.16f, 0.18f, 0.21f, 1};
  const float light[4] = {0.23f, 0.26f, 0.30f, 1};
  for (int i = -half_tiles; i < half_tiles; ++i) {
    for (int j = -half_tiles; j < half_tiles; ++j) {
      if (scn.ngeom >= scn.maxgeom) return;
      mjvGeom* g = scn.geoms + scn.ngeom++;
      const mjtNum size[3] = {0.5 * tile, 0.5 * tile, 0.5 * tile};
      const mjtNum pos[3] = {x0 + (i + 0.5) * tile, y0 + (j + 0.5) * tile, z};
      mjv_initGeom(g, mjGEOM_PLANE, size, pos, nullptr, ((i + j) & 1) ? light : dark);
      g->category = mjCAT_DECOR;
      g->specular = 0.1f;
    }
  }
}

// a shadow-casting light from above and behind the camera, for models without lights
void add_key_light(mjvScene& scn, const Bounds& motion, const Vec3& view_forward) {
  if (scn.nlight >= mjMAXLIGHT) return;
  mjvLight& light = scn.lights[scn.nlight++];
  std::memset(&light, 0, sizeof(light));
  Vec3 dir{0.6 * view_forward[0], 0.6 * view_forward[1], 0.6 * view_forward[2] - 1};
  const double norm = std::sqrt(vdot(dir, dir));
  const Vec3 c = motion.center();
  const double back = 2 * motion.size() + 1;
  for (std::size_t i = 0; i < 3; ++i) {
    dir[i] /= norm;
    light.pos[i] = static_cast<float>(c[i] - back * dir[i]);
    light.dir[i] = static_cast<float>(dir[i]);
    light.ambient[i] = 0.1f;
    light.diffuse[i] = 0.6f;
    light.specular[i] = 0.2f;
  }
  light.attenuation[0] = 1;
  light.cutoff = 180;
  light.directional = 1;
  light.castshadow = 1;
}

// luminance-preserving recolouring of a run's moving geoms (dark parts stay darker)
void recolour(mjvScene& scn, int from, const Rgb& rgb) {
  auto lum = [](const float* c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; };
  float lum_max = 1e-3f;
  for (int i = from; i < scn.ngeom; ++i) {
    if (scn.geoms[i].category == mjCAT_DYNAMIC) lum_max = std::max(lum_max, lum(scn.geoms[i].rgba));
  }
  for (int i = from; i < scn.ngeom; ++i) {
    mjvGeom& g = scn.geoms[i];
    if (g.category != mjCAT_DYNAMIC || g.objtype != mjOBJ_GEOM) continue;
    const float shade = 0.4f + 0.6f * std::min(1.0f, lum(g.rgba) / lum_max);
    for (std::size_t k = 0; k < 3; ++k) g.rgba[k] = rgb[k] * shade;
    g.rgba[3] = 1;
    g.texid = -1;
    g.reflectance = 0;
    g.transparent = 0;
  }
}

// thins a geom across its long axis by `factor`; returns its half-thickness before
float thin_geom(mjvGeom& g, float factor) {
  switch (g.type) {
    case mjGEOM_SPHERE:
    case mjGEOM_CAPSULE:
    case mjGEOM_CYLINDER:
      g.size[0] *= factor;
      return g.size[0] / factor;
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID: {
      const auto longest = std::max_element(g.size, g.size + 3) - g.size;
      float across = 0;
      for (int k = 0; k < 3; ++k) {
        if (k == longest) continue;
        across = std::max(across, g.size[k]);
        g.size[k] *= factor;
      }
      return across;
    }
    default:
      return g.modelrbound;
  }
}

// a run's moving geoms become thin cores moved towards the camera by more than the other
// arm's thickness, so they are drawn on top of it wherever the two arms coincide
void make_cores(mjvScene& scn, int from, const Vec3& eye) {
  float across = 0;
  for (int i = from; i < scn.ngeom; ++i) {
    mjvGeom& g = scn.geoms[i];
    if (g.category == mjCAT_DYNAMIC && g.objtype == mjOBJ_GEOM) {
      across = std::max(across, thin_geom(g, kCoreScale));
    }
  }
  const double lift = 1.1 * across * (1 + kCoreScale);
  for (int i = from; i < scn.ngeom; ++i) {
    mjvGeom& g = scn.geoms[i];
    if (g.category != mjCAT_DYNAMIC || g.objtype != mjOBJ_GEOM) continue;
    const Vec3 to_eye = vsub(eye, Vec3{g.pos[0], g.pos[1], g.pos[2]});
    const double dist = std::sqrt(vdot(to_eye, to_eye));
    if (dist <= 2 * lift) continue;
    for (std::size_t k = 0; k < 3; ++k) g.pos[k] += static_cast<float>(lift * to_eye[k] / dist);
  }
}

// a vertical gradient wherever nothing was drawn (depth still 1), for models without a skybox
void draw_sky(int width, int height) {
  glViewport(0, 0, width, height);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glOrtho(0, 1, 0, 1, -1, 1);
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glDisable(GL_LIGHTING);
  glDisable(GL_TEXTURE_2D);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_STENCIL_TEST);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_FALSE);
  glShadeModel(GL_SMOOTH);
  const float z = -0.99999f;  // window depth just below the cleared 1.0
  glBegin(GL_QUADS);
  glColor3f(kSkyHorizon[0], kSkyHorizon[1], kSkyHorizon[2]);
  glVertex3f(0, 0, z);
  glVertex3f(1, 0, z);
  glColor3f(kSkyTop[0], kSkyTop[1], kSkyTop[2]);
  glVertex3f(1, 1, z);
  glVertex3f(0, 1, z);
  glEnd();
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LEQUAL);
}

// ------------------------------------------------------------------------------- overlay

std::string time_text(double t, double speed) {
  std::string s = fmt("%.3f s", t);
  if (std::fabs(speed - 1) > 1e-9) s += "  (" + fmt("%g", speed) + "x speed)";
  return s;
}

// single run: key / value rows
std::vector<Row> single_rows(const Replay& r, double t, double speed) {
  const std::size_t row = r.log->nearest_row(t);
  std::vector<Row> rows;
  rows.push_back({{{"time", kKey}, {time_text(t, speed)}}});
  rows.push_back({{{"controller", kKey}, {r.log->label}}});
  rows.push_back({{{"|u|", kKey}, {value_text("%.3f N m", r.log->u_norm(row))}}});
  rows.push_back({{{"residual", kKey}, {value_text("%.3e", r.log->residual[row])}}});
  rows.push_back({{{"update", kKey}, {value_text("%.3f ms", r.log->update_ms[row])}}});
  const std::string status = r.status(t);
  if (!status.empty()) rows.push_back({{{"status", kKey}, {status, kAlert}}});
  return rows;
}

// compare: the time, then per run a legend line and a line of values
std::vector<Row> compare_rows(const std::vector<Replay>& replays, const std::vector<Rgb>& colours,
                              double t, double speed) {
  std::vector<Row> rows;
  rows.push_back({{{"time  " + time_text(t, speed), kWhite}}});
  for (std::size_t i = 0; i < replays.size(); ++i) {
    const Replay& r = replays[i];
    const std::size_t row = r.log->nearest_row(t);
    Row legend;
    legend.swatch = true;
    legend.swatch_rgb = colours[i];
    legend.cells = {{r.log->label, colours[i]}};
    rows.push_back(legend);
    Row values;
    values.cells = {{"|u| " + value_text("%.3f", r.log->u_norm(row)), kWhite},
                    {"res " + value_text("%.2e", r.log->residual[row]), kWhite},
                    {value_text("%.3f", r.log->update_ms[row]) + " ms", kWhite}};
    const std::string status = r.status(t);
    if (!status.empty()) values.cells.push_back({status, kAlert});
    rows.push_back(values);
  }
  return rows;
}

// |u| over time until the log ends or turns non-finite
std::vector<std::array<float, 2>> u_curve(const Replay& r, const Schedule& s) {
  std::vector<std::array<float, 2>> curve;
  for (int i = 0; i < kPlotSamples; ++i) {
    const double t = s.t0 + (s.t_end - s.t0) * i / (kPlotSamples - 1);
    if (t < r.log->t.front() - 1e-9) continue;
    if (t > r.log->t.back() + 1e-9) break;
    const double u = r.log->u_norm(r.log->nearest_row(t));
    if (!std::isfinite(u)) break;
    curve.push_back({static_cast<float>(t), static_cast<float>(u)});
  }
  return curve;
}

// (MuJoCo 2.2 renders mjFONTSCALE_50 as 100: 100 is the smallest)
int font_scale_for(int height) {
  if (height < 600) return mjFONTSCALE_100;
  if (height < 1000) return mjFONTSCALE_150;
  return mjFONTSCALE_200;
}

// pixel rectangle -> normalized device coordinates
ScreenRegion to_ndc(const mjrRect& r, int width, int height) {
  return {2.0 * r.left / width - 1, 2.0 * (r.left + r.width) / width - 1,
          2.0 * r.bottom / height - 1, 2.0 * (r.bottom + r.height) / height - 1};
}

// where the motion may go: the frame minus a margin, beside or above/below each overlay;
// one candidate region per combination
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

// the camera: a fixed one of the model, or a free one placed so the whole motion fits in one
// of the free regions (a planar motion seen square-on, a spatial one from the front left)
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

}  // namespace

void check_video_options(const VideoOptions& options) {
  for (const auto& [name, v] : {std::pair<const char*, int>{"--width", options.width},
                                std::pair<const char*, int>{"--height", options.height}}) {
    if (v < 2 || v > kMaxSize || v % 2 != 0) {
      throw std::invalid_argument(std::string(name) + ": expected an even number of pixels in 2.." +
                                  std::to_string(kMaxSize) + " (H.264 yuv420p), got " +
                                  std::to_string(v));
    }
  }
  if (!(options.fps > 0) || options.fps > kMaxFps) {
    throw std::invalid_argument("--fps: expected 0 < fps <= " + fmt("%g", kMaxFps) + ", got " +
                                fmt("%g", options.fps));
  }
  if (!(options.speed > 0) || options.speed > kMaxSpeed) {
    throw std::invalid_argument("--speed: expected 0 < speed <= " + fmt("%g", kMaxSpeed) +
                                ", got " + fmt("%g", options.speed));
  }
  parse_camera(options.camera);
}

void render_video(const std::string& model_path, const std::vector<RunLog>& runs,
                  const VideoOptions& options, const std::string& out_mp4,
                  const std::function<void(double)>& progress) {
  // everything cheap is checked before any GL or ffmpeg work
  check_video_options(options);
  if (runs.empty() || runs.size() > 2) {
    throw std::invalid_argument("runs: expected one log (or two to compare), got " +
                                std::to_string(runs.size()));
  }
  mj::ModelPtr model = mj::load_model(model_path);
  mjModel* m = model.get();
  for (const RunLog& run : runs) check_run_log(run, m, model_path);
  const CameraSpec camera_spec = parse_camera(options.camera);
  const int fixed_camid = find_fixed_camera(m, camera_spec, model_path);
  check_output_writable(out_mp4);
  if (find_on_path("ffmpeg").empty()) {
    throw std::runtime_error("ffmpeg not found on PATH: install the Debian package ffmpeg");
  }

  // compare mode: the FD run (or else the first) is the blue arm, the other the orange core
  const bool compare = runs.size() == 2;
  std::vector<std::size_t> order{0};
  if (compare) order = (runs[0].formulation == "id" && runs[1].formulation != "id")
                           ? std::vector<std::size_t>{1, 0}
                           : std::vector<std::size_t>{0, 1};
  std::vector<Replay> replays;
  std::vector<Rgb> colours;
  for (std::size_t i : order) {
    replays.emplace_back(runs[i]);
    colours.push_back(compare ? (replays.size() == 1 ? kBlue : kOrange) : kSinglePlot);
  }
  const Schedule schedule = make_schedule(replays, options);
  std::vector<mj::DataPtr> data_owner;
  std::vector<mjData*> datas;
  for (std::size_t r = 0; r < replays.size(); ++r) {
    data_owner.push_back(mj::make_data(m));
    datas.push_back(data_owner.back().get());
  }
  mjvOption opt;
  mjv_defaultOption(&opt);
  const Motion motion = measure_motion(m, datas, replays, schedule, opt);

  // GL: OSMesa context and MuJoCo's off-screen buffer at the video size
  GlContext gl(options.width, options.height);
  m->vis.global.offwidth = options.width;
  m->vis.global.offheight = options.height;
  RenderContext context(m, font_scale_for(options.height));
  mjrContext& con = context.con;
  mjr_setBuffer(mjFB_OFFSCREEN, &con);
  if (con.currentBuffer != mjFB_OFFSCREEN) {
    throw std::runtime_error("MuJoCo could not select its off-screen framebuffer");
  }
  const mjrRect viewport{0, 0, options.width, options.height};

  // overlays: a table top left (sized for its widest frame), the |u| plot bottom right
  auto rows_at = [&](double t) {
    return compare ? compare_rows(replays, colours, t, options.speed)
                   : single_rows(replays[0], t, options.speed);
  };
  TableLayout table(con);
  for (long k = 0; k < schedule.frames; ++k) table.fit(rows_at(schedule.time(k)));
  const int margin = std::max(4, options.height / 80);
  const mjrRect table_rect{margin, options.height - margin - table.height(), table.width(),
                           table.height()};
  // compare: the second run's curve dashed on top, like its arm's stripe on the first
  std::vector<PlotCurve> curves;
  for (std::size_t r = 0; r < replays.size(); ++r) {
    curves.push_back({u_curve(replays[r], schedule), colours[r], r > 0});
  }
  TimePlot plot("|u| [N m]", schedule.t0, schedule.t_end, curves);
  const int plot_w = std::max(24 * con.charWidth[static_cast<unsigned char>('0')],
                              options.width * 30 / 100);
  const int plot_h = std::max(8 * con.charHeight, options.height * 28 / 100);
  const mjrRect plot_rect{options.width - plot_w - margin, margin, plot_w, plot_h};
  // a small video keeps the table and drops the plot rather than stack them
  const bool show_table = options.overlay;
  const bool show_plot = options.overlay &&
                         table.height() + plot_h + 3 * margin <= options.height &&
                         plot_w <= options.width / 2;
  std::vector<ScreenRegion> overlays;
  if (show_table) overlays.push_back(to_ndc(table_rect, options.width, options.height));
  if (show_plot) overlays.push_back(to_ndc(plot_rect, options.width, options.height));

  // camera
  FreeCamera free_cam;
  mjvCamera cam = make_camera(m, camera_spec, fixed_camid, motion, free_regions(overlays),
                              static_cast<double>(options.width) / options.height, free_cam);
  Vec3 view_forward, view_up, view_right;
  camera_axes(free_cam.azimuth, free_cam.elevation, view_forward, view_up, view_right);

  // scene dressing where the model has none
  const bool dress_floor = !has_plane(m);
  const bool dress_light = m->nlight == 0;
  const bool dress_sky = !has_skybox(m);
  Scene scene(m, static_cast<int>(replays.size()) * m->ngeom + 1200);
  mjvScene& scn = scene.scn;

  VideoWriter writer(out_mp4, options.width, options.height, options.fps);
  const std::size_t row_bytes = static_cast<std::size_t>(options.width) * 3;
  std::vector<unsigned char> pixels(row_bytes * static_cast<std::size_t>(options.height));
  std::vector<unsigned char> frame(pixels.size());

  for (long k = 0; k < schedule.frames; ++k) {
    const double t = schedule.time(k);
    for (std::size_t r = 0; r < replays.size(); ++r) set_pose(m, datas[r], replays[r], t);

    // the scene: the first run (all categories), then the second run's moving geoms
    mjv_updateScene(m, datas[0], &opt, nullptr, &cam, mjCAT_ALL, &scn);
    if (compare) {
      const Vec3 eye{0.5 * (scn.camera[0].pos[0] + scn.camera[1].pos[0]),
                     0.5 * (scn.camera[0].pos[1] + scn.camera[1].pos[1]),
                     0.5 * (scn.camera[0].pos[2] + scn.camera[1].pos[2])};
      recolour(scn, 0, colours[0]);
      const int first = scn.ngeom;
      mjv_addGeoms(m, datas[1], &opt, nullptr, mjCAT_DYNAMIC, &scn);
      recolour(scn, first, colours[1]);
      make_cores(scn, first, eye);
    }
    if (dress_floor) add_floor(scn, motion.visible);
    if (dress_light) add_key_light(scn, motion.visible, view_forward);
    mjr_render(viewport, &scn, &con);
    if (dress_sky) draw_sky(options.width, options.height);

    // overlays
    if (show_table) table.draw(rows_at(t), table_rect.left, table_rect.bottom + table_rect.height);
    if (show_plot) plot.draw(plot_rect, t, con);

    // read back (GL rows run bottom-up) and encode
    mjr_readPixels(pixels.data(), nullptr, viewport, &con);
    for (int y = 0; y < options.height; ++y) {
      std::memcpy(frame.data() + static_cast<std::size_t>(y) * row_bytes,
                  pixels.data() + static_cast<std::size_t>(options.height - 1 - y) * row_bytes,
                  row_bytes);
    }
    writer.write_frame(frame.data());
    if (progress) progress(static_cast<double>(k + 1) / static_cast<double>(schedule.frames));
  }
  writer.finish();
}

}  // namespace idmpc::render
