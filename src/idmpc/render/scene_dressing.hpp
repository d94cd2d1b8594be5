#pragma once
/// @file scene_dressing.hpp
/// @brief What the renderer adds to or changes in a MuJoCo scene: a floor, a light and a sky
/// where the model has none, and the compare mode's per-run colours (a solid arm and a thinner
/// core drawn just in front of it).

#include <mujoco/mujoco.h>

#include "idmpc/render/framing.hpp"
#include "idmpc/render/overlay.hpp"

namespace idmpc::render {

/// compare mode: the FD run (or else the first) solid blue
inline constexpr Rgb kBlue = {0.18f, 0.48f, 1.00f};
/// compare mode: the other run a thinner solid orange core
inline constexpr Rgb kOrange = {1.00f, 0.52f, 0.08f};

/// @brief Whether a scene geom belongs to one of the robot's moving bodies (a body with a joint
/// between it and the world). Static world geometry is not: the world body's geoms and those of
/// bodies no joint moves (a base, a table, a mocap target), whatever their MuJoCo category.
bool moving_geom(const mjModel* m, const mjvGeom& g);

/// @brief Removes the model geoms of static bodies from scene geoms `from` on: a second run
/// adds only its moving bodies (MuJoCo's dynamic category also holds mocap bodies).
void keep_moving_geoms(mjvScene& scn, const mjModel* m, int from);

/// @brief Whether the model has a ground plane.
bool has_plane(const mjModel* m);

/// @brief Whether the model has a skybox texture.
bool has_skybox(const mjModel* m);

/// @brief Appends a checkered floor below the motion, for models without a ground plane.
void add_floor(mjvScene& scn, const Bounds& motion);

/// @brief Appends a shadow-casting light from above and behind the camera, for models without
/// lights.
void add_key_light(mjvScene& scn, const Bounds& motion, const Vec3& view_forward);

/// @brief Recolours a run's moving geoms (scene geoms from index `from` on; static world
/// geometry keeps its colours) in `rgb`, preserving their relative luminance (dark parts stay
/// darker).
void recolour(mjvScene& scn, const mjModel* m, int from, const Rgb& rgb);

/// @brief Turns a run's moving geoms (from index `from` on) into thin cores moved towards the
/// eye by more than the other arm's thickness, so they are drawn on top of it wherever the two
/// arms coincide.
void make_cores(mjvScene& scn, const mjModel* m, int from, const Vec3& eye);

/// @brief Draws a vertical gradient wherever nothing was drawn (depth still 1), for models
/// without a skybox; call after mjr_render on a width x height viewport.
void draw_sky(int width, int height);

}  // namespace idmpc::render
