#pragma once
/// @file rnea.hpp
/// @brief Recursive Newton–Euler algorithm (Featherstone 2008, Table 5.1) with armature and
/// passive joint forces: ID(q, v, a) = M a + c(q, v) − passive(q, v) (formulations.md §The model).

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {
namespace detail {

// RNEA's backward pass from the body forces in data.F: joint torques with armature and passive
// forces into data.tau, subtree forces accumulated into data.F
template <typename S, typename Q, typename Vv, typename Aa>
[[gnu::flatten]] void rnea_backward(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                   const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<Aa>& a) {
  for (int i = model.n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    data.tau[i] = joint_project<S>(model, i, data.F[i]) +
                  armature_and_passive<S>(model, i, S(q[i]), S(v[i]), S(a[i]));
    if (p >= 0) data.F[p] += data.X_up[i].apply_transpose_force(data.F[i]);
  }
}

// the weight that gravity compensation carries, off link i's body force: F_i −= I_gravcomp,i·Ag_i
// (Ag_i = X_{i,0}·a0 = −g in link i's frame; an upward force c_b·m_b·g at each body's centre
// of mass)
template <typename S> void subtract_gravcomp(const Model& model, DataTpl<S>& data, int i) {
  data.F[i] -= cast_inertia<S>(model.I_gravcomp[i]).apply(data.Ag[i]);
}

}  // namespace detail

/// @brief Inverse dynamics τ = ID(q, v, a); q, v, a of size n. Fills data.X_up, V, A, h, vJ
/// and the subtree forces F (used by rnea_vjp). Returns data.tau.
template <typename S, typename Q, typename Vv, typename Aa>
[[gnu::flatten]] const VecX<S>& rnea(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                    const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<Aa>& a) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n, "rnea: data was made for a model of another size");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea()), "rnea: data was made without its rnea part");
  IDMPC_CHECK_ARGUMENT(q.size() == model.n && v.size() == model.n && a.size() == model.n,
                    "rnea: q, v, a must have size model.n");
  IDMPC_CHECK_ARGUMENT(!model.gravcomp || data.Ag.size() == static_cast<std::size_t>(model.n),
                       "rnea: data was made for a model without gravity compensation");
  data.passes.rnea(q);
  const Vec6<S> a0 = base_acceleration<S>(model);
  // forward pass: link velocities, accelerations and body forces
  for (int i = 0; i < model.n; ++i) {
    const int p = model.parent[i];
    joint_transform<S>(model, i, S(q[i]), data.X_up[i]);
    data.vJ[i].setZero();
    add_joint_motion<S>(model, i, S(v[i]), data.vJ[i]);
    if (p < 0) {
      data.V[i] = data.vJ[i];
      data.A[i] = data.X_up[i].apply_motion(a0);
    } else {
      data.V[i] = data.X_up[i].apply_motion(data.V[p]) + data.vJ[i];
      data.A[i] = data.X_up[i].apply_motion(data.A[p]) + cross_motion<S>(data.V[i], data.vJ[i]);
    }
    add_joint_motion<S>(model, i, S(a[i]), data.A[i]);
    const auto& Ii = cast_inertia<S>(model.I[i]);
    data.h[i] = Ii.apply(data.V[i]);
    data.F[i] = Ii.apply(data.A[i]) + cross_force<S>(data.V[i], data.h[i]);
    if (model.gravcomp) {
      data.Ag[i] = data.X_up[i].apply_motion(p < 0 ? a0 : data.Ag[p]);
      detail::subtract_gravcomp(model, data, i);
    }
  }
  detail::rnea_backward(model, data, q, v, a);
  return data.tau;
}

/// @brief τ = ID(q, v, q̈) at the point (q, v) of the last aba call, q̈ = data.qdd (so τ is
/// the aba's torque up to rounding), reusing aba's link kinematics: its joint transforms,
/// velocities and the accelerations of its last pass are rnea's at that point. Only the body
/// forces and the backward pass remain. Leaves data as rnea(q, v, data.qdd) would, for
/// rnea_vjp, and keeps aba's factorization for minv_apply. Returns data.tau.
/// Precondition: data holds aba at (q, v) (checked in debug builds).
template <typename S, typename Q, typename Vv>
[[gnu::flatten]] const VecX<S>& rnea_after_aba(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                              const Eigen::MatrixBase<Vv>& v) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && q.size() == model.n && v.size() == model.n,
                    "rnea_after_aba: q, v must have size model.n");
  IDMPC_DEBUG_CHECK(data.passes.holds_aba_at(q, v),
                    "rnea_after_aba needs aba(model, data, q, v, tau) at this (q, v) first, and no "
                    "other algorithm at another q since");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea() | DataParts::aba()),
                    "rnea_after_aba: data was made without its rnea and aba parts");
  data.passes.rnea_after_aba();
  // body forces
  for (int i = 0; i < model.n; ++i) {
    const auto& Ii = cast_inertia<S>(model.I[i]);
    data.h[i] = Ii.apply(data.V[i]);
    data.F[i] = Ii.apply(data.A[i]) + cross_force<S>(data.V[i], data.h[i]);
    if (model.gravcomp) detail::subtract_gravcomp(model, data, i);
  }
  detail::rnea_backward(model, data, q, v, data.qdd);
  return data.tau;
}

}  // namespace idmpc
