#pragma once
/// @file crba.hpp
/// @brief Composite-rigid-body algorithm (Featherstone 2008, Table 6.2): M(q) with armature.
///
/// Leaves first, in link frames: the force Ic_i·S_i of every link visited so far is kept in the
/// set data.Fc (one column per link, at its depth-first position), each expressed in the frame
/// of the link being visited. At link i the columns of i's subtree, consecutive there, give row
/// i of M by projection on S_i; then one transform carries all of them to the parent's frame
/// with vector loops over the set (as Pinocchio's local-convention crba), and Ic_i is added to
/// the parent's composite inertia.

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief Joint-space inertia M(q) (n×n, symmetric, armature on the diagonal). Returns data.M.
/// Also leaves data.X_up at q.
template <typename S, typename Q>
[[gnu::flatten]] const MatX<S>& crba(const Model& model, DataTpl<S>& data,
                                     const Eigen::MatrixBase<Q>& q) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n, "crba: data was made for a model of another size");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea() | DataParts::crba()), "crba: data was made without its rnea and crba parts");
  IDMPC_CHECK_ARGUMENT(q.size() == model.n, "crba: q must have size model.n");
  data.passes.kinematics(q);
  data.passes.mass_matrix();
  const int n = model.n;
  for (int i = 0; i < n; ++i) {
    joint_transform<S>(model, i, S(q[i]), data.X_up[i]);
    data.Ic[i] = cast_inertia<S>(model.I[i]);
  }
  SpatialSet<S>& F = data.Fc;
  S* M = data.M.data();  // column-major n×n; a plain pointer, not reloaded after each store
  for (int i = n - 1; i >= 0; --i) {
    // i's descendants are done: Ic_i is complete and their forces are in i's frame
    const int b = model.preorder_index[i], e = b + model.subtree_size[i];
    F.col(b) = inertia_times_motion_subspace<S>(model, i, data.Ic[i]);
    project_columns<S>(model, i, F, b, e, [&](int t, const S& x) {
      const int j = model.preorder[t];
      M[i * n + j] = x;
      M[j * n + i] = x;
    });
    M[i * n + i] += armature_passive_partials(model, i).da;
    const int p = model.parent[i];
    if (p < 0) continue;
    data.Ic[i].add_transformed_to_parent(data.X_up[i], data.Ic[p]);
    data.X_up[i].apply_transpose_force_to_columns(F, b, e);
  }
  return data.M;
}

}  // namespace idmpc
