#pragma once
/// @file reference.hpp
/// @brief MuJoCo's own dynamics on the same file, as the reference our algorithms must match:
/// mj_inverse (qfrc_inverse), mj_forward (qacc, constraints off), mj_fullM and mj_solveM.

#include <mujoco/mujoco.h>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc::mj {

class Reference {
 public:
  /// Copies the model and disables constraints and actuation in the copy, so that
  /// generalized forces enter through qfrc_applied only.
  explicit Reference(const mjModel* m);

  int nv() const { return m_->nv; }
  /// @brief qfrc_inverse of mj_inverse at (q, v, a).
  VecX<double> inverse(const VecX<double>& q, const VecX<double>& v, const VecX<double>& a);
  /// @brief qacc of mj_forward at (q, v) with qfrc_applied = τ.
  VecX<double> forward(const VecX<double>& q, const VecX<double>& v, const VecX<double>& tau);
  /// @brief Dense M(q) from mj_fullM.
  MatX<double> mass_matrix(const VecX<double>& q);
  /// @brief M(q)⁻¹x by mj_solveM with the sparse LTDL factor of mj_forward at q.
  VecX<double> solve_mass(const VecX<double>& q, const VecX<double>& x);

  const mjModel* model() const { return m_.get(); }
  mjData* data() { return d_.get(); }

 private:
  void set_state(const VecX<double>& q, const VecX<double>& v);
  ModelPtr m_;
  DataPtr d_;
};

}  // namespace idmpc::mj
