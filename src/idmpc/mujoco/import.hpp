#pragma once
/// @file import.hpp
/// @brief mjModel → Model, following DESIGN §3 exactly, plus how torques reach the plant.

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/model/model.hpp"

namespace idmpc::mj {

struct ImportOptions {
  /// Ignore the model's own actuators (whatever their kind) and apply joint torques directly
  /// through qfrc_applied, e.g. for servo-actuated robot files.
  bool direct_torque = false;
};

/// @brief How a joint torque vector τ reaches the plant.
struct Actuation {
  bool direct = true;                ///< τ → qfrc_applied (actuation disabled)
  std::vector<int> actuator_of_dof;  ///< else ctrl[actuator_of_dof[i]] = τ_i · ctrl_per_torque[i]
  std::vector<double> ctrl_per_torque;
  /// Joint torque range each actuator can give (ctrlrange × gain × gear, forcerange × gear);
  /// ±infinity where unlimited, and always with direct torques.
  VecX<double> torque_lower, torque_upper;
};

struct ImportedModel {
  Model model;
  Actuation actuation;
  std::vector<std::string> unmodeled;  ///< plant features the controller's model ignores
};

/// @brief Builds the controller's Model from a MuJoCo model. Throws std::invalid_argument
/// naming the element for anything unsupported (ball/free joints, non-motor actuators,
/// under-actuation). `source` names the file in messages.
ImportedModel import_model(const mjModel* m, const std::string& source,
                           const ImportOptions& options = {});

/// @brief qpos of the keyframe called `name`; throws std::invalid_argument naming the model if
/// it has none.
VecX<double> keyframe_qpos(const mjModel* m, const std::string& name, const std::string& source);

/// @brief One message per joint whose value in q (named `what`, e.g. "q0") lies outside the
/// joint's range, for limited joints.
std::vector<std::string> range_violations(const mjModel* m, const VecX<double>& q, const std::string& what);

}  // namespace idmpc::mj
