#pragma once
/// @file hold.hpp
/// @brief Joints the controller holds instead of driving: a gripper's fingers that the model
/// moves through a tendon actuator (fingers coupled by a fixed tendon, a joint equality, …)
/// rather than with one actuator per joint.
///
/// The controller's model welds them where they are held, so that their bodies' masses and
/// inertias ride on the link that carries them; its coordinates are the other joints. The plant
/// keeps every joint: the model's own actuators hold the fingers, each at the control whose rest
/// is the held position, and MuJoCo's tendons and equality constraints couple them as published.
/// What the held fingers still do to the arm (a finger that moves, its servo's reaction) is a
/// disturbance, which the offset-free observer takes up.
///
/// Which joints are held (joints_to_hold): joints the arm carries (some joint above each has an
/// actuator of its own) that have no actuator of their own, moved (at qpos0) by an actuator
/// without a joint transmission that moves only such joints; and the joints of that kind that an
/// active equality constraint ties to those (joint equalities; connect and weld equalities through the joints between their
/// two bodies; tendon equalities through the tendons' joints). A held joint may carry no joint
/// that is not held.

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc::mj {

struct HeldJoints {
  std::vector<int> joints;         ///< the full model's joints, increasing
  std::vector<std::string> names;  ///< their names
  VecX<double> q;                  ///< where each is held (its qpos)
  std::vector<int> qpos_of;        ///< per held joint: its qpos (and dof) index
  std::vector<int> actuators;      ///< the full model's actuators that hold them
  VecX<double> ctrl;               ///< their controls: each one's rest at the held position
  std::vector<int> dof_of;         ///< per dof of the controller's model: the full model's dof
  std::vector<int> actuator_of;    ///< per actuator of the controller's model: the full model's
  bool empty() const { return joints.empty(); }
  /// @brief The full model's qpos with the controller's q and the held joints where held.
  VecX<double> full_q(const VecX<double>& q_controller) const;
  /// @brief The controller's coordinates of a full qpos (or qvel).
  VecX<double> controlled(const VecX<double>& full) const;
  /// @brief One line: which joints are held, by which actuators, where.
  std::string notice(const mjModel* full) const;
};

/// @brief The joints of `m` the controller holds (the rule above), increasing; empty if none.
/// Throws std::invalid_argument naming the joints if a held joint carries one that is not held.
std::vector<int> joints_to_hold(const mjModel* m, const std::string& source);

/// @brief `joints` of `m` held at their values in `qpos` (the full model's nq), with the
/// controls of their actuators and the maps between the two models' dofs and actuators.
HeldJoints hold_joints(const mjModel* m, const std::vector<int>& joints, const VecX<double>& qpos);

/// @brief The controller's model: the file of `full` with the joints of `held` welded where
/// held (load_model_translated with a Weld). Throws std::runtime_error naming the file if the
/// welded model does not have the dofs and actuators `held` expects.
LoadedModel load_held_model(const std::string& path, const mjModel* full, const HeldJoints& held);

/// @brief A model file as the controller sees it: the whole model (the plant's), the joints
/// held, and the controller's model (the whole one when nothing is held).
struct ControllerModel {
  LoadedModel full;
  HeldJoints held;
  LoadedModel welded;  ///< empty when nothing is held
  const LoadedModel& controller() const { return held.empty() ? full : welded; }
  const mjModel* model() const { return controller().model.get(); }
};

/// @brief Loads `path` (load_model_translated) and, unless `hold` is false (direct torques drive
/// every joint), holds the joints of joints_to_hold where the keyframe `keyframe` has them, or
/// at qpos0 when `keyframe` is empty. Throws as load_model_translated and joints_to_hold, and
/// std::invalid_argument naming the model for a keyframe it does not have.
ControllerModel load_controller_model(const std::string& path, const std::string& keyframe = "", bool hold = true);

}  // namespace idmpc::mj
