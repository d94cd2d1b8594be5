#pragma once
/// @file crba.hpp
/// @brief Composite-rigid-body algorithm (Featherstone 2008, Table 6.2): M(q) with armature.
///
/// On trees deeper than three ancestors per link on average, computed in the world frame, as
/// Pinocchio's crba: every body inertia is placed in the world once, composite inertias are then
/// plain sums, and M_ij = S_jᵀ·(Ic_i S_i) for j = i and each ancestor j of i is one 6-vector dot
/// product, with no transform per (i, j) pair. On shallow trees the world placements cost more
/// than they save, and the force Ic_i S_i is carried up the ancestors in link frames instead.

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief Joint-space inertia M(q) (n×n, symmetric, armature on the diagonal). Returns data.M.
/// Also leaves data.X_up at q.
template <typename S, typename Q>
const MatX<S>& crba(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q) {
  IDMPC_DEBUG_CHECK(data.n == model.n, "crba: data was made for a model of another size");
  IDMPC_DEBUG_CHECK(q.size() == model.n, "crba: q must have size model.n");
  data.passes.kinematics(q);
  data.passes.mass_matrix();
  const int n = model.n;
  if (model.ancestor_pairs <= 3 * n) {
    // shallow: composite inertias in link frames, leaves first
    for (int i = 0; i < n; ++i) {
      data.X_up[i] = joint_transform<S>(model, i, S(q[i]));
      data.Ic[i] = cast_inertia<S>(model.I[i]);
    }
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
  // world placements, joint axes and body inertias
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    data.X_up[i] = joint_transform<S>(model, i, S(q[i]));
    data.oX[i] = p < 0 ? data.X_up[i] : data.X_up[i] * data.oX[p];
    data.oS[i] = motion_subspace_in<S>(model, i, data.oX[i]);
    data.oI[i] = cast_inertia<S>(model.I[i]).transformed_to_parent(data.oX[i]);
  }
  // leaves first: Ic_i is complete when i is reached; column i is the force Ic_i·S_i
  // projected on the axes of i and of its ancestors
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    const Vec6<S> F = data.oI[i].apply(data.oS[i]);
    data.M(i, i) = data.oS[i].dot(F) + armature_passive_partials(model, i).da;
    for (int j = p; j >= 0; j = model.parent[j]) {
      data.M(i, j) = data.M(j, i) = data.oS[j].dot(F);
    }
    if (p >= 0) data.oI[p] += data.oI[i];
  }
  return data.M;
}

}  // namespace idmpc
