#pragma once
/// @file load.hpp
/// @brief Loading MuJoCo models with MuJoCo's errors turned into C++ exceptions.

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/mujoco/mjcf_translate.hpp"

namespace idmpc::mj {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

/// @brief Installs handlers so that a MuJoCo error throws std::runtime_error (instead of
/// exiting) and MuJoCo warnings are collected, and the passive-force callback that applies
/// gravity compensation (gravcomp.hpp). Idempotent, thread-safe.
void install_error_handlers();

/// @brief Warnings MuJoCo raised through mju_warning since the last call (then cleared).
std::vector<std::string> take_warnings();

/// @brief A loaded model with what its translation from MuJoCo >= 2.3 MJCF did.
struct LoadedModel {
  ModelPtr model;
  std::string source;                     ///< the file loaded
  std::vector<Translation> translations;  ///< one per translation; empty if none was needed
  /// Torque range per joint (mjModel joint index) that the file declares with actuatorfrcrange on
  /// a joint no actuator drives; ±infinity elsewhere (njnt entries each).
  std::vector<double> joint_force_lower, joint_force_upper;
  /// @brief One short line that names the kinds of translation made, with their counts ("" if
  /// none); `translations` holds each in full (idmpc check prints them).
  std::string notice() const;
};

/// @brief Loads an MJCF or URDF file; throws std::runtime_error naming the file and the problem
/// in one line if the file is missing, unreadable, no regular file (a directory, FIFO or
/// device: refused before it is opened for reading), larger than 64 MiB, includes itself or a
/// file twice, or is malformed: an attribute, value or element of a newer
/// MuJoCo than this build's (mj_versionString()), a missing mesh or texture file (named as MuJoCo
/// looks for it), or MuJoCo's own message.
///
/// Before MuJoCo parses the file, it and its includes are scanned for NaN or infinity in an
/// attribute of the physics (mass, density, inertia, pos, range, ctrlrange, damping, gear, …):
/// MuJoCo 2.2 compiles those or quietly ignores them (a geom's mass="nan" becomes the density's
/// mass); such a model is refused naming the element, its line and the attribute. They are also
/// scanned for images MuJoCo would
/// allocate in full: a builtin or PNG texture, or a height field, of more than 8192 x 8192 pixels
/// is refused (such a model would take gigabytes or crash MuJoCo 2.2 inside mj_loadXML).
///
/// MJCF written for MuJoCo >= 2.3 is translated in memory first (mjcf_translate.hpp: the user's
/// files are read, never written): MuJoCo parses the translated text of the changed files (the
/// others, meshes and textures still come from disk, resolved as MuJoCo 2.2 resolves them), and
/// what only the compiler knows is set in the compiled model. What has no MuJoCo 2.2 equivalent
/// is listed all at once in the one-line error, each item with its element, name, attribute and
/// line. A file that needs no translation is loaded exactly as written.
///
/// With `weld`, the joints it names are welded in the text MuJoCo parses (Weld): the
/// controller's model of an arm whose gripper it holds (hold.hpp).
LoadedModel load_model_translated(const std::string& path, const Weld* weld = nullptr);

/// @brief load_model_translated(path).model: the translations are not reported.
ModelPtr load_model(const std::string& path);

/// @brief Loads a model from MJCF text (written to a temporary file); for tests.
ModelPtr load_model_from_string(const std::string& xml);

/// @brief Makes mjData for a model; throws on failure.
DataPtr make_data(const mjModel* m);

/// @brief mjData at `qpos` (nq values) with the positions, tendons and actuator transmissions
/// computed (actuator_length, actuator_moment), as MuJoCo's compiler computes them at qpos0.
DataPtr transmission_at(const mjModel* m, const mjtNum* qpos);

/// @brief Name of an object (joint, body, actuator, ...) or "#id" when it has none.
std::string object_name(const mjModel* m, mjtObj type, int id);
/// @brief The actuator object_name called `name` (one of that name, else "#id" of an unnamed
/// one), or -1.
int actuator_id(const mjModel* m, const std::string& name);

}  // namespace idmpc::mj
