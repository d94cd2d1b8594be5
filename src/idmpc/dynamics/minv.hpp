#pragma once
/// @file minv.hpp
/// @brief The dense inverse M(q)⁻¹ without forming M: the ABA sweeps of the n unit loads, in
/// the world frame, where forces and accelerations need no transform between links.

#include <algorithm>

#include "idmpc/dynamics/aba.hpp"

namespace idmpc {

namespace detail {

/// @brief data.Minv ← M(q)⁻¹ from an articulated-body factorization in the world frame at q:
/// data.oUD = U/D and Dinv = 1/D per joint, axes data.oS. Backward, column j's unit load travels
/// up j's ancestors only (the rows of the upper triangle above j; four columns at a time, whose
/// chains are independent); forward, row i takes the columns j ≥ i; the lower triangle is the
/// mirror.
template <typename S> [[gnu::flatten]] void minv_world_sweeps(const Model& model, DataTpl<S>& data, const VecX<S>& Dinv) {
  const int n = model.n;
  auto& Minv = data.Minv;
  // backward: articulated forces of the unit loads, one 6-vector per column
  Minv.template triangularView<Eigen::StrictlyUpper>().setZero();
  constexpr int kColumns = 4;
  for (int j0 = 0; j0 < n; j0 += kColumns) {
    Vec6<S> P[kColumns];
    int at[kColumns];  // the ancestor each column's load has reached, −1 when done
    for (int k = 0; k < kColumns; ++k) {
      const int j = j0 + k;
      at[k] = -1;
      P[k].setZero();  // unused past n; set so that no path reads it uninitialized
      if (j >= n) continue;
      Minv(j, j) = Dinv[j];
      P[k] = data.oUD[j];
      at[k] = model.parent[j];
    }
    while (std::max(std::max(at[0], at[1]), std::max(at[2], at[3])) >= 0) {
      for (int k = 0; k < kColumns; ++k) {
        const int i = at[k];
        if (i < 0) continue;
        const S u = -data.oS[i].dot(P[k]);
        Minv(i, j0 + k) = u * Dinv[i];
        P[k] += data.oUD[i] * u;
        at[k] = model.parent[i];
      }
    }
  }
  // forward: accelerations of every column j ≥ i, root first
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    const Vec6<S>& Si = data.oS[i];
    const Vec6<S>& UDi = data.oUD[i];
    auto& Ai = data.Am[i];
    if (p < 0) {
      for (int j = i; j < n; ++j) Ai.col(j) = Si * Minv(i, j);
    } else {
      const auto& Ap = data.Am[p];
      for (int j = i; j < n; ++j) {
        const S y = Minv(i, j) - UDi.dot(Ap.col(j));
        Minv(i, j) = y;
        Ai.col(j) = Ap.col(j) + Si * y;
      }
    }
  }
  // symmetric: the lower triangle from the upper
  for (int j = 0; j < n; ++j) {
    for (int i = j + 1; i < n; ++i) Minv(i, j) = Minv(j, i);
  }
}

/// @brief World placements data.oX and axes data.oS from the joint transforms data.X_up.
template <typename S> void world_placements(const Model& model, DataTpl<S>& data) {
  for (int i = 0; i < model.n; ++i) {
    const int p = model.parent[i];
    data.oX[i] = p < 0 ? data.X_up[i] : data.X_up[i] * data.oX[p];
    data.oS[i] = motion_subspace_in<S>(model, i, data.oX[i]);
  }
}

}  // namespace detail

/// @brief data.Minv ← M(q)⁻¹ (dense, n×n) in O(n·depth + n²) from the articulated inertias of
/// the last aba(q, ·, ·) call. Returns data.Minv; also leaves the world placements data.oX and
/// axes data.oS at q. Precondition: data holds aba at q (checked in debug builds).
template <typename S> const MatX<S>& minv_matrix_after_aba(const Model& model, DataTpl<S>& data) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n,
                    "minv_matrix_after_aba: data was made for a model of another size");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::aba() | DataParts::rnea_derivatives() | DataParts::minv_matrix()),
                    "minv_matrix_after_aba: data was made without its aba, rnea_derivatives and minv_matrix parts");
  IDMPC_DEBUG_CHECK(data.passes.holds_aba(),
                    "minv_matrix_after_aba needs aba(model, data, q, v, tau) first, and no other "
                    "algorithm at another q since");
  detail::world_placements(model, data);
  for (int i = 0; i < model.n; ++i) data.oUD[i] = data.oX[i].apply_transpose_force(data.Ud[i]);
  detail::minv_world_sweeps(model, data, data.Dinv);
  return data.Minv;
}

/// @brief data.Minv ← M(q)⁻¹ (dense, n×n) from q alone, as Pinocchio's computeMinverse: the
/// articulated inertias of ABA without velocities or forces, accumulated in the world frame
/// (a rank-1 update per joint, no transform of a 6×6 matrix), then the sweeps of the unit
/// loads. Returns data.Minv; leaves data.X_up, oX, oS at q (an aba factorization in data stays
/// valid only if it was made at the same q).
template <typename S, typename Q>
[[gnu::flatten]] const MatX<S>& minv_matrix(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && q.size() == model.n, "minv_matrix: q must have size model.n");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea() | DataParts::rnea_derivatives() | DataParts::minv_matrix()),
                    "minv_matrix: data was made without its rnea, rnea_derivatives and minv_matrix parts");
  data.passes.kinematics(q);
  const int n = model.n;
  // world placements, axes and body inertias
  for (int i = 0; i < n; ++i) {
    joint_transform<S>(model, i, S(q[i]), data.X_up[i]);
  }
  detail::world_placements(model, data);
  for (int i = 0; i < n; ++i) {
    data.oYA[i] = cast_inertia<S>(model.I[i]).transformed_to_parent(data.oX[i]).matrix();
  }
  // articulated inertias, leaves first: Y_λ += Y_i − U Uᵀ/D, U = Y_i S_i
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    const Vec6<S> U = data.oYA[i] * data.oS[i];
    data.oDinv[i] = S(1) / (data.oS[i].dot(U) + armature_passive_partials(model, i).da);
    data.oUD[i] = U * data.oDinv[i];
    if (p >= 0) {
      data.oYA[p] += data.oYA[i];
      data.oYA[p].noalias() -= U * data.oUD[i].transpose();
    }
  }
  detail::minv_world_sweeps(model, data, data.oDinv);
  return data.Minv;
}

}  // namespace idmpc
