#include "idmpc/render/scene_dressing.hpp"

#include <GL/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace idmpc::render {
namespace {

constexpr float kCoreScale = 0.45f;  // the core's cross-section relative to the arm's

// sky gradient drawn behind the scene when the model has no skybox
constexpr Rgb kSkyTop = {0.11f, 0.13f, 0.17f};
constexpr Rgb kSkyHorizon = {0.42f, 0.47f, 0.54f};

Vec3 vsub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double vdot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

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

}  // namespace

bool moving_geom(const mjModel* m, const mjvGeom& g) {
  if (g.objtype != mjOBJ_GEOM || g.objid < 0 || g.objid >= m->ngeom) return false;
  return m->body_weldid[m->geom_bodyid[g.objid]] != 0;
}

void keep_moving_geoms(mjvScene& scn, const mjModel* m, int from) {
  // compact in place: other objects (decor, sites) stay, static model geoms go
  int kept = from;
  for (int i = from; i < scn.ngeom; ++i) {
    const mjvGeom& g = scn.geoms[i];
    if (g.objtype == mjOBJ_GEOM && !moving_geom(m, g)) continue;
    if (kept != i) scn.geoms[kept] = g;
    ++kept;
  }
  scn.ngeom = kept;
}

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

void add_floor(mjvScene& scn, const Bounds& motion) {
  // round tiles on a grid centred below the motion, under its lowest point
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

void add_key_light(mjvScene& scn, const Bounds& motion, const Vec3& view_forward) {
  if (scn.nlight >= mjMAXLIGHT) return;
  mjvLight& light = scn.lights[scn.nlight++];
  std::memset(&light, 0, sizeof(light));
  // directional, tilted down from the view direction, placed well outside the motion
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

void recolour(mjvScene& scn, const mjModel* m, int from, const Rgb& rgb) {
  auto lum = [](const float* c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; };
  // the brightest moving geom maps to the full colour
  float lum_max = 1e-3f;
  for (int i = from; i < scn.ngeom; ++i) {
    if (moving_geom(m, scn.geoms[i])) lum_max = std::max(lum_max, lum(scn.geoms[i].rgba));
  }
  // solid, untextured, unreflective: the colour alone tells the run
  for (int i = from; i < scn.ngeom; ++i) {
    mjvGeom& g = scn.geoms[i];
    if (!moving_geom(m, g)) continue;
    const float shade = 0.4f + 0.6f * std::min(1.0f, lum(g.rgba) / lum_max);
    for (std::size_t k = 0; k < 3; ++k) g.rgba[k] = rgb[k] * shade;
    g.rgba[3] = 1;
    g.texid = -1;
    g.reflectance = 0;
    g.transparent = 0;
  }
}

void make_cores(mjvScene& scn, const mjModel* m, int from, const Vec3& eye) {
  // thin every moving geom, remembering the thickest arm cross-section
  float across = 0;
  for (int i = from; i < scn.ngeom; ++i) {
    mjvGeom& g = scn.geoms[i];
    if (moving_geom(m, g)) across = std::max(across, thin_geom(g, kCoreScale));
  }
  // pull each towards the eye by more than that
  const double lift = 1.1 * across * (1 + kCoreScale);
  for (int i = from; i < scn.ngeom; ++i) {
    mjvGeom& g = scn.geoms[i];
    if (!moving_geom(m, g)) continue;
    const Vec3 to_eye = vsub(eye, Vec3{g.pos[0], g.pos[1], g.pos[2]});
    const double dist = std::sqrt(vdot(to_eye, to_eye));
    if (dist <= 2 * lift) continue;
    for (std::size_t k = 0; k < 3; ++k) g.pos[k] += static_cast<float>(lift * to_eye[k] / dist);
  }
}

void draw_sky(int width, int height) {
  // a unit square in window space, depth-tested just in front of the cleared depth
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
  // horizon colour at the bottom, sky colour at the top
  glBegin(GL_QUADS);
  glColor3f(kSkyHorizon[0], kSkyHorizon[1], kSkyHorizon[2]);
  glVertex3f(0, 0, z);
  glVertex3f(1, 0, z);
  glColor3f(kSkyTop[0], kSkyTop[1], kSkyTop[2]);
  glVertex3f(1, 1, z);
  glVertex3f(0, 1, z);
  glEnd();
  // restore MuJoCo's depth state
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LEQUAL);
}

}  // namespace idmpc::render
