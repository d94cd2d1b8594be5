#pragma once
/// @file aba.hpp
/// @brief Articulated-body algorithm (Featherstone 2008, Table 7.1) with armature and passive
/// forces: FD(q, v, τ) = M⁻¹(τ − c + passive) (formulations.md §The model), and M⁻¹x reusing its factorization.

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief Forward dynamics q̈ = FD(q, v, τ); q, v, τ of size n. Returns data.qdd and leaves
/// the articulated inertias (data.IA, U, D, and Ud = U/D, Dinv = 1/D) for minv_apply and
/// minv_matrix_after_aba. ABA itself divides by D (multiplying by Dinv timed the same).
template <typename S, typename Q, typename Vv, typename T>
[[gnu::flatten]] const VecX<S>& aba(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                   const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<T>& tau) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n, "aba: data was made for a model of another size");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea() | DataParts::aba()), "aba: data was made without its rnea and aba parts");
  IDMPC_CHECK_ARGUMENT(q.size() == model.n && v.size() == model.n && tau.size() == model.n,
                    "aba: q, v, tau must have size model.n");
  IDMPC_CHECK_ARGUMENT(!model.gravcomp || data.Ag.size() == static_cast<std::size_t>(model.n),
                       "aba: data was made for a model without gravity compensation");
  data.passes.aba(q, v);
  const int n = model.n;
  const Vec6<S> a0 = base_acceleration<S>(model);
  // pass 1: velocities, velocity-product accelerations, rigid-body inertias and bias forces
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    // a local transform for the motion transform right below (reading data.X_up back here
    // timed 2 % slower than the in-place write saves)
    Transform<S> X;
    joint_transform<S>(model, i, S(q[i]), X);
    data.X_up[i] = X;
    data.vJ[i].setZero();
    add_joint_motion(model, i, S(v[i]), data.vJ[i]);
    data.V[i] = p < 0 ? data.vJ[i] : Vec6<S>(X.apply_motion(data.V[p]) + data.vJ[i]);
    data.c[i] = cross_motion<S>(data.V[i], data.vJ[i]);
    const Inertia<S> Ii = cast_inertia<S>(model.I[i]);
    data.IA[i] = Ii.matrix();
    data.pA[i] = cross_force<S>(data.V[i], Ii.apply(data.V[i]));
    if (model.gravcomp) {
      // the compensation's upward force is an external force on the link
      data.Ag[i] = X.apply_motion(p < 0 ? a0 : data.Ag[p]);
      data.pA[i] -= cast_inertia<S>(model.I_gravcomp[i]).apply(data.Ag[i]);
    }
  }
  // pass 2: articulated inertias and bias forces, leaves first
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    data.U[i] = times_motion_subspace<S>(model, i, data.IA[i]);
    data.D[i] = joint_project<S>(model, i, data.U[i]) + armature_passive_partials(model, i).da;
    data.Dinv[i] = S(1) / data.D[i];  // for the sweeps of the dense M⁻¹ (minv.hpp)
    data.Ud[i] = data.U[i] * data.Dinv[i];
    data.u[i] = tau[i] - joint_project<S>(model, i, data.pA[i]) -
                armature_and_passive<S>(model, i, S(q[i]), S(v[i]), S(0));
    if (p >= 0) {
      const Mat6<S> Ia = data.IA[i] - data.U[i] * data.U[i].transpose() / data.D[i];
      const Vec6<S> pa = data.pA[i] + Ia * data.c[i] + data.U[i] * (data.u[i] / data.D[i]);
      data.IA[p] += congruence_to_parent<S>(Ia, data.X_up[i]);
      data.pA[p] += data.X_up[i].apply_transpose_force(pa);
    }
  }
  // pass 3: accelerations, root first
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    const Vec6<S> ap = data.X_up[i].apply_motion(p < 0 ? a0 : data.A[p]) + data.c[i];
    data.qdd[i] = (data.u[i] - data.U[i].dot(ap)) / data.D[i];
    data.A[i] = ap;
    add_joint_motion(model, i, data.qdd[i], data.A[i]);
  }
  return data.qdd;
}

/// @brief y = M(q)⁻¹x in O(n), reusing the articulated inertias of the last aba(q, ·, ·) call
/// (an ABA sweep with zero velocity and gravity). Returns data.Minv_x.
///
/// The sweeps carry x's articulated bias forces to the root and the accelerations back, one
/// joint after the other. What does not depend on x is taken off that chain: U/D of each joint
/// in its parent's frame, Y_i = X_upᵀ·U_i/D_i (data.Ud_parent), so that a force reaches the
/// parent as X_upᵀp_i + Y_i·u_i and a joint's acceleration is u_i/D_i − Y_i·a_parent, with
/// the transforms of p_i and a_parent beside, not before, the products with Y_i.
/// Precondition: data holds aba at q (checked in debug builds).
template <typename S, typename Xx>
[[gnu::flatten]] const VecX<S>& minv_apply(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Xx>& x) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && x.size() == model.n, "minv_apply: x must have size model.n");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::minv_apply()), "minv_apply: data was made without its minv_apply part");
  IDMPC_DEBUG_CHECK(data.passes.holds_aba(),
                    "minv_apply needs aba(model, data, q, v, tau) first, and no other algorithm at "
                    "another q since");
  const int n = model.n;
  for (int i = 0; i < n; ++i) data.pz[i].setZero();
  // backward: articulated bias forces of the load x, u_i = x_i − S_iᵀp_i
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    const S u = x[i] - joint_project<S>(model, i, data.pz[i]);
    data.Minv_x[i] = u;
    if (p >= 0) {
      const Transform<S>& X = data.X_up[i];
      data.Ud_parent[i] = X.apply_transpose_force(data.Ud[i]);
      data.pz[p] += X.apply_transpose_force(data.pz[i]) + data.Ud_parent[i] * u;
    }
  }
  // forward: accelerations, root first
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    S y = data.Minv_x[i] * data.Dinv[i];
    if (p < 0) {
      data.az[i].setZero();
    } else {
      y -= data.Ud_parent[i].dot(data.az[p]);
      data.az[i] = data.X_up[i].apply_motion(data.az[p]);
    }
    data.Minv_x[i] = y;
    add_joint_motion(model, i, y, data.az[i]);
  }
  return data.Minv_x;
}

/// @brief data.rhs ← M(q)⁻¹·data.rhs for its first m columns (m ≤ n) in one pair of
/// sweeps of 6×m blocks, reusing the articulated inertias of the last aba(q, ·, ·) call.
/// Precondition: data holds aba at q (checked in debug builds).
template <typename S> void minv_apply_columns(const Model& model, DataTpl<S>& data, int m) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && m >= 0 && m <= model.n,
                    "minv_apply_columns: expected 0 <= m <= model.n");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::minv_columns()),
                    "minv_apply_columns: data was made without its minv_columns part");
  IDMPC_DEBUG_CHECK(data.passes.holds_aba(),
                    "minv_apply_columns needs aba(model, data, q, v, tau) first, and no other "
                    "algorithm at another q since");
  const int n = model.n;
  auto Y = data.rhs.leftCols(m);
  for (int i = 0; i < n; ++i) data.Pm[i].leftCols(m).setZero();
  // backward: articulated bias forces of every load column
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    auto P = data.Pm[i].leftCols(m);
    auto yi = Y.row(i);
    subtract_joint_projection(model, i, P, yi);
    if (p >= 0) {
      // Pm[p] += X_upᵀ (P + U u / D), force transform of each column
      const Transform<S>& X = data.X_up[i];
      auto T = data.Tm.leftCols(m);
      auto W = data.Wm.leftCols(m);
      T = P;
      T.noalias() += Vec6<S>(data.U[i] / data.D[i]) * Y.row(i);
      W.noalias() = X.E.transpose() * T.template bottomRows<3>();
      auto Pp = data.Pm[p].leftCols(m);
      Pp.template bottomRows<3>() += W;
      Pp.template topRows<3>().noalias() += X.E.transpose() * T.template topRows<3>();
      Pp.template topRows<3>().noalias() += skew<S>(X.r) * W;
    }
  }
  // forward: accelerations of every column
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    auto A = data.Am[i].leftCols(m);
    if (p < 0) {
      A.setZero();
    } else {
      // motion transform of each column: [E ω; E (v − r × ω)]
      const Transform<S>& X = data.X_up[i];
      auto Ap = data.Am[p].leftCols(m);
      auto W = data.Wm.leftCols(m);
      W = Ap.template bottomRows<3>();
      W.noalias() -= skew<S>(X.r) * Ap.template topRows<3>();
      A.template topRows<3>().noalias() = X.E * Ap.template topRows<3>();
      A.template bottomRows<3>().noalias() = X.E * W;
    }
    Y.row(i).noalias() -= data.U[i].transpose() * A;
    Y.row(i) /= data.D[i];
    add_joint_motion(model, i, Y.row(i), A);
  }
}

}  // namespace idmpc
