#pragma once
/// @file crba.hpp
/// @brief Composite-rigid-body algorithm (Featherstone 2008, Table 6.2): M(q) with armature.

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief Joint-space inertia M(q) (n×n, symmetric, armature on the diagonal). Returns data.M.
template <typename S, typename Q>
const MatX<S>& crba(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q) {
  IDMPC_DEBUG_CHECK(data.n == model.n, "crba: data was made for a model of another size");
  IDMPC_DEBUG_CHECK(q.size() == model.n, "crba: q must have size model.n");
  data.passes.kinematics(q);
  const int n = model.n;
  for (int i = 0; i < n; ++i) {
    data.X_up[i] = joint_transform<S>(model, i, S(q[i]));
    data.Ic[i] = cast_inertia<S>(model.I[i]);
  }
  // composite inertias, leaves first
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    if (p >= 0) data.Ic[p] += data.Ic[i].transformed_to_parent(data.X_up[i]);
  }
  // column i: the force Ic·S_i carried up to every ancestor
  for (int i = 0; i < n; ++i) {
    Vec6<S> f = data.Ic[i].apply(motion_subspace<S>(model, i));
    data.M(i, i) = joint_project<S>(model, i, f) + armature_passive_partials(model, i).da;
    for (int j = i; model.parent[j] >= 0;) {
      f = data.X_up[j].apply_transpose_force(f);
      j = model.parent[j];
      data.M(i, j) = data.M(j, i) = joint_project<S>(model, j, f);
    }
  }
  return data.M;
}

}  // namespace idmpc
