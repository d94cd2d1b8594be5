#pragma once
/// @file import.hpp
/// @brief mjModel → Model, following formulations.md §The model exactly, plus how torques reach the plant.

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/model/frame.hpp"
#include "idmpc/model/model.hpp"

namespace idmpc::mj {

struct ImportOptions {
  /// Ignore the model's own actuators (whatever their kind) and apply joint torques directly
  /// through qfrc_applied, e.g. for tendon-driven or muscle robot files.
  bool direct_torque = false;
  /// Confirms that direct torques (direct_torque, or servos replaced by torques) may drive the
  /// joints that no actuator of the model drives; without it such an under-actuated model is
  /// refused.
  bool actuate_every_joint = false;
  /// Torque range per joint (mjModel joint index) that the file declares for joints no actuator
  /// drives (LoadedModel::joint_force_lower/upper, from actuatorfrcrange); empty: none. They
  /// bound the torques of those joints.
  std::vector<double> joint_force_lower, joint_force_upper;
};

/// @brief How a joint torque vector τ reaches the plant.
///
/// - Motors (fixed gain, no bias, no activation dynamics, one per joint): τ → ctrl.
/// - Servos (fixed gain and affine bias: `<position>`, `<velocity>`, `<intvelocity>`, `<general>`
///   servos, with or without activation dynamics, one per joint with a joint transmission) are
///   replaced by joint torques: τ → qfrc_applied, the plant disables actuation, and each servo's
///   forcerange × gear (when force-limited) bounds its joint's torque. The servo's control and
///   activation ranges are positions or velocities, not torques, and do not bound τ.
/// - Direct (no actuators, or ImportOptions::direct_torque): τ → qfrc_applied.
/// - Under-actuated: joints no actuator drives (and that no confirmation lets direct torques
///   drive) are passive: the plant applies no torque there, whatever τ holds.
struct Actuation {
  bool direct = true;                ///< τ → qfrc_applied (actuation disabled)
  std::vector<int> actuator_of_dof;  ///< else ctrl[actuator_of_dof[i]] = τ_i · ctrl_per_torque[i]
  std::vector<double> ctrl_per_torque;
  /// Joint torque range each actuator can give (ctrlrange × gain × gear, forcerange × gear; a
  /// replaced servo's forcerange × gear, or without one its derived_limits), intersected with
  /// ImportOptions::joint_force_lower/upper;
  /// ±infinity where unlimited, and with ImportOptions::direct_torque where the file declares none.
  VecX<double> torque_lower, torque_upper;
  /// Names of the servo actuators replaced by joint torques (then `direct`), in actuator order.
  std::vector<std::string> replaced_servos;
  /// @brief Replaced servos without a forcerange whose torque range is derived: the force they
  /// give at rest (gain·ctrl + b0 + b1·q) over their control range and their joint's range (the
  /// control range where the joint has none), times the gear.
  std::vector<std::string> derived_limits;
  /// Joints whose torque has no declared bound on either side ("joint 'j1'"), in dof order.
  std::vector<std::string> unbounded_joints;
  /// Joints no actuator of the model drives, actuated by direct torques on the user's
  /// confirmation (ImportOptions::actuate_every_joint).
  std::vector<std::string> unactuated_joints;
  /// Dofs no actuator drives and no direct torque may drive (without
  /// ImportOptions::actuate_every_joint): the model is under-actuated, these joints are passive
  /// (Link::actuated false; their torque limits ±infinity), increasing.
  std::vector<int> passive_dofs;
  bool passive(int dof) const { return std::binary_search(passive_dofs.begin(), passive_dofs.end(), dof); }
  /// Joints without an actuator that an active joint equality ties to an actuated joint (mimic
  /// joints), driven by direct torques within that joint's range: (name, the actuated joint's name).
  std::vector<std::pair<std::string, std::string>> coupled_joints;
  /// @brief One line: what drives the joints and what bounds their torques.
  std::string summary() const;
};

struct ImportedModel {
  Model model;
  Actuation actuation;
  std::vector<std::string> unmodeled;  ///< plant features the controller's model ignores
  /// What the import changed in how the model is driven (servos replaced by joint torques,
  /// joints without an actuator actuated, torques without a bound), one line each.
  std::vector<std::string> notices;
};

/// @brief Builds the controller's Model from a MuJoCo model. Throws std::invalid_argument
/// naming the element for anything unsupported: ball/free joints; actuators neither motors nor
/// servos (muscles, user gains), on a tendon, site or body, or two on one joint (unless
/// direct_torque). Joints without an actuator are passive (an under-actuated model) unless the
/// torques are direct and actuate_every_joint lets them drive every joint. `source` names the
/// file in messages.
ImportedModel import_model(const mjModel* m, const std::string& source,
                           const ImportOptions& options = {});

/// @brief The Frame of the site called `name`, or else of the body called `name` ("world": the
/// base), on the links import_model(m, …) makes: a site's placement is its body's composed with
/// site_pos/site_quat, a body's is where its frame sits on the link it is rigidly attached to.
/// Throws std::invalid_argument naming `source` and `name`, with the model's site names, if
/// there is neither; or for what import_model refuses in the joints, or a non-finite placement.
Frame import_frame(const mjModel* m, const std::string& name, const std::string& source);

/// @brief qpos of the keyframe called `name`; throws std::invalid_argument naming the model if
/// it has none.
VecX<double> keyframe_qpos(const mjModel* m, const std::string& name, const std::string& source);

/// @brief One message per joint whose value in q (named `what`, e.g. "q0") lies outside the
/// joint's range, for limited joints.
std::vector<std::string> range_violations(const mjModel* m, const VecX<double>& q, const std::string& what);

}  // namespace idmpc::mj
