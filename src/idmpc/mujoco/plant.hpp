#pragma once
/// @file plant.hpp
/// @brief The robot in the loop: MuJoCo's mj_step on the full model (contacts, limits and all).

#include <string>

#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc::mj {

class Plant {
 public:
  /// Keeps its own copy of the model; direct actuation disables the model's actuators.
  Plant(const mjModel* m, const Actuation& actuation);

  int nv() const { return m_->nv; }
  double timestep() const { return m_->opt.timestep; }
  /// @brief Sets the control period: each step() holds the torque for dt. If dt is a whole
  /// multiple of the model's timestep, step() makes that many MuJoCo steps; otherwise the
  /// model's timestep is replaced by dt and the returned warning says so (else empty).
  std::string set_control_period(double dt);
  int substeps() const { return substeps_; }
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

  Eigen::Map<const VecX<double>> q() const { return {d_->qpos, m_->nq}; }
  Eigen::Map<const VecX<double>> v() const { return {d_->qvel, m_->nv}; }
  double time() const { return d_->time; }
  const mjModel* model() const { return m_.get(); }

 private:
  ModelPtr m_;
  DataPtr d_;
  // applies τ to the actuators or qfrc_applied
  void apply(const VecX<double>& tau);

  Actuation actuation_;
  int substeps_ = 1;
  long contact_steps_ = 0;
  double max_contact_force_ = 0;
};

}  // namespace idmpc::mj
