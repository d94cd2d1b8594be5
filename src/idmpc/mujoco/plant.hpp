#pragma once
/// @file plant.hpp
/// @brief The robot in the loop: MuJoCo's mj_step on the full model (contacts, limits and all).

#include <string>

#include "idmpc/mujoco/hold.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc::mj {

class Plant {
 public:
  /// Keeps its own copy of the model; direct actuation disables the model's actuators. With
  /// held joints (hold.hpp), `actuation` is the controller's model's: the plant's coordinates
  /// (q, v, τ) are the controller's, the held joints' own actuators hold them at their controls,
  /// and direct actuation zeroes the force of the other actuators instead.
  Plant(const mjModel* m, const Actuation& actuation, const HeldJoints& held = {});

  /// the dofs the controller sees (the model's nv without held joints)
  int nv() const { return static_cast<int>(dof_of_.size()); }
  double timestep() const { return m_->opt.timestep; }
  /// @brief Sets the control period: each step() holds the torque for dt. If dt is a whole
  /// multiple of the model's timestep, step() makes that many MuJoCo steps; otherwise the
  /// model's timestep is replaced by dt and the returned warning says so (else empty).
  std::string set_control_period(double dt);
  int substeps() const { return substeps_; }
  /// @brief The state (q, v) in the controller's coordinates; held joints where held, at rest.
  void reset(const VecX<double>& q, const VecX<double>& v);
  /// @brief Applies τ (through the motors or qfrc_applied) for one step. Returns false with
  /// a reason if the state became non-finite or MuJoCo raised a warning (e.g. bad qacc).
  bool step(const VecX<double>& tau, std::string* reason);
  /// @brief One step whose torque changes within it, as a late torque arrives (compute latency,
  /// formulations.md §Compute latency): τ_before for the first `switch_at` of its substeps() MuJoCo steps (0 to
  /// substeps()), τ_after for the rest. Returns as step().
  bool step(const VecX<double>& tau_before, int switch_at, const VecX<double>& tau_after, std::string* reason);

  /// @brief Control steps since reset() during which MuJoCo had at least one contact, and the
  /// largest contact normal force seen [N] (mj_contactForce).
  long contact_steps() const { return contact_steps_; }
  double max_contact_force() const { return max_contact_force_; }

  /// @brief The measured state in the controller's coordinates.
  VecX<double> q() const;
  VecX<double> v() const;
  /// @brief The whole model's qpos, held joints included (for its kinematics).
  Eigen::Map<const VecX<double>> full_q() const { return {d_->qpos, m_->nq}; }
  double time() const { return d_->time; }
  /// @brief The whole model (with held joints; the indices of sites and bodies are the
  /// controller's model's).
  const mjModel* model() const { return m_.get(); }

 private:
  ModelPtr m_;
  DataPtr d_;
  // applies τ to the actuators or qfrc_applied
  void apply(const VecX<double>& tau);

  Actuation actuation_;
  HeldJoints held_;
  std::vector<int> dof_of_;       // per controller dof: the model's dof
  std::vector<int> actuator_of_;  // per actuator of the controller's model: the model's
  int substeps_ = 1;
  long contact_steps_ = 0;
  double max_contact_force_ = 0;
};

}  // namespace idmpc::mj
