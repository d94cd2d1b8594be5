#pragma once
/// @file rnea_vjp.hpp
/// @brief Vector–Jacobian products of RNEA in one O(n) reverse sweep (formulations.md §Derivatives):
/// (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw and (∂ID/∂a)ᵀw = M·w, by reverse-mode differentiation of the
/// link-frame recursion of rnea.hpp.
///
/// Adjoint of the backward pass (a forward sweep): f̄_i = X_i f̄_λ(i) + S_i w_i.
/// Adjoint of the forward pass (a backward sweep), from f_i = I_i a_i + v_i ×* I_i v_i,
/// a_i = X_i a_λ + S_i q̈_i + v_i × S_i q̇_i, v_i = X_i v_λ + S_i q̇_i and ∂X_i/∂q_i = −S_i× X_i:
///   ā_i += I_i f̄_i;   v̄_i += −f̄_i ×* h_i − I_i (v_i × f̄_i) + (S_i q̇_i) ×* ā_i
///   (∂τ/∂a)ᵀw = Sᵀā,  (∂τ/∂v)ᵀw = Sᵀv̄ + ā·(v × S),
///   (∂τ/∂q)ᵀw = (f̄ × S)·F_i + ā·((X a_λ) × S) + v̄·((X v_λ) × S).
/// Gravity compensation, f_i −= Ig_i Ag_i with Ag_i = X_i Ag_λ (rnea.hpp), adds its own adjoint
/// ḡ_i = −Ig_i f̄_i + Σ_children X_cᵀ ḡ_c and the term ḡ_i·(Ag_i × S_i) to (∂τ/∂q)ᵀw.

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M·w into data.g_q, g_v, g_a. Precondition: data holds
/// rnea(model, data, q, v, a) at the point of linearization (w of size n); checked in debug
/// builds, as far as data can tell: no algorithm since has overwritten rnea's link velocities
/// and accelerations (aba) or recomputed the kinematics at another q.
template <typename S, typename W>
[[gnu::flatten]] void rnea_vjp(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<W>& w) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && w.size() == model.n, "rnea_vjp: w must have size model.n");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea_vjp()), "rnea_vjp: data was made without its rnea_vjp part");
  IDMPC_DEBUG_CHECK(data.passes.holds_rnea(),
                    "rnea_vjp needs rnea(model, data, q, v, a) at the point of linearization "
                    "first, and no aba or algorithm at another q since");
  IDMPC_CHECK_ARGUMENT(!model.gravcomp || data.gbar.size() == static_cast<std::size_t>(model.n),
                       "rnea_vjp: data was made for a model without gravity compensation");
  const int n = model.n;
  const bool gravcomp = model.gravcomp;
  // adjoint of the backward pass: force adjoints propagate root to leaves like velocities
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    const Vec6<S> Si = motion_subspace<S>(model, i);
    data.fbar[i] = Si * w[i];
    if (p >= 0) data.fbar[i] += data.X_up[i].apply_motion(data.fbar[p]);
    data.g_q[i] = cross_motion<S>(data.fbar[i], Si).dot(data.F[i]);
    data.abar[i].setZero();
    data.vbar[i].setZero();
    if (gravcomp) data.gbar[i].setZero();
  }
  // adjoint of the forward pass: leaves to root
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    const Vec6<S> Si = motion_subspace<S>(model, i);
    const Inertia<S> Ii = cast_inertia<S>(model.I[i]);
    // body force f = I a + v ×* I v
    data.abar[i] += Ii.apply(data.fbar[i]);
    data.vbar[i] += -cross_force<S>(data.fbar[i], data.h[i]) -
                    Ii.apply(cross_motion<S>(data.V[i], data.fbar[i])) +
                    cross_force<S>(data.vJ[i], data.abar[i]);
    // joint inputs, with armature, damping and stiffness
    const ArmaturePassivePartials d = armature_passive_partials(model, i);
    data.g_a[i] = Si.dot(data.abar[i]) + d.da * w[i];
    // the joint velocity from vJ = S v (S of unit norm) for the friction's slope
    const S dv = d.dv + friction_slope<S>(model, i, joint_project<S>(model, i, data.vJ[i]));
    data.g_v[i] = Si.dot(data.vbar[i]) + data.abar[i].dot(cross_motion<S>(data.V[i], Si)) + dv * w[i];
    // joint angle through X_i in a_i = X_i a_λ + … and v_i = X_i v_λ + …; (X_i a_λ) × S_i
    // equals (a_i − v_i × S_i q̇_i) × S_i since S_i × S_i = 0
    const Vec6<S> Xa = data.A[i] - cross_motion<S>(data.V[i], data.vJ[i]);
    data.g_q[i] += data.abar[i].dot(cross_motion<S>(Xa, Si)) + d.dq * w[i];
    if (gravcomp) {
      // f_i −= Ig_i Ag_i with Ag_i = X_i Ag_λ: its adjoint, through X_i like the acceleration's
      data.gbar[i] -= cast_inertia<S>(model.I_gravcomp[i]).apply(data.fbar[i]);
      data.g_q[i] += data.gbar[i].dot(cross_motion<S>(data.Ag[i], Si));
      if (p >= 0) data.gbar[p] += data.X_up[i].apply_transpose_force(data.gbar[i]);
    }
    if (p >= 0) {
      data.g_q[i] += data.vbar[i].dot(cross_motion<S>(Vec6<S>(data.V[i] - data.vJ[i]), Si));
      data.abar[p] += data.X_up[i].apply_transpose_force(data.abar[i]);
      data.vbar[p] += data.X_up[i].apply_transpose_force(data.vbar[i]);
    }
  }
}

}  // namespace idmpc
