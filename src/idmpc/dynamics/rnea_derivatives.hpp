#pragma once
/// @file rnea_derivatives.hpp
/// @brief Analytic partial derivatives of RNEA (in the spirit of Carpentier & Mansard, RSS 2018):
/// ∂τ/∂q, ∂τ/∂v and ∂τ/∂a = M, from world-frame quantities in O(n·depth).
///
/// With world-frame joint axes S_j, velocities v, accelerations a (base: −g), composite
/// inertias Ic_i, subtree forces F_i and composite "Coriolis" matrices
/// Bc_i = Σ_{k∈sub(i)} (−I_k [v_k]× + [v_k]×* I_k + [h_k]‾), h_k = I_k v_k,
/// and per joint w_j = S_j × v_λ(j), ψ_j = S_j × a_λ(j) − w_j × v_λ(j):
///   j ancestor of i (or i):  ∂τ_i/∂q_j = −(Ic_i S_i)·ψ_j − (Bc_iᵀ S_i)·w_j
///                            ∂τ_i/∂v_j = (Bc_iᵀ S_i)·S_j − 2 (Ic_i S_i)·w_j
///   j descendant of i:       ∂τ_i/∂q_j = S_i·(−Ic_j ψ_j − Bc_j w_j + S_j ×* F_j)
///                            ∂τ_i/∂v_j = S_i·(Bc_j S_j − 2 Ic_j w_j)
/// plus stiffness, damping and armature on the diagonals. Gravity compensation (the composite
/// compensated inertias Ig_i, at rest, with ψg_j = S_j × a0) adds (Ig_i S_i)·ψg_j to the first
/// line and S_i·(Ig_j ψg_j) to the third, and takes Ig_j·a0 off F_j.

#include "idmpc/model/data.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief B = [v]×*·I − I·[v]× + [h]‾ (h = I v) in 3×3 blocks: with W = [ω]×, V = [v_lin]×,
/// H = [m c]×, N = [h_ang]×, F = [h_lin]× and the symmetry of Ibar, three 3×3 products suffice.
template <typename S>
Mat6<S> coriolis_matrix(const Inertia<S>& I, const Vec6<S>& v, const Vec6<S>& h) {
  const Mat3<S> W = skew<S>(v.template head<3>()), V = skew<S>(v.template tail<3>());
  const Mat3<S> H = skew<S>(I.h), N = skew<S>(h.template head<3>()), F = skew<S>(h.template tail<3>());
  const Mat3<S> WI = W * I.Ibar, VH = V * H, WH = W * H;
  const Mat3<S> TR = WH - WH.transpose() + I.m * V;
  Mat6<S> B;
  B.template topLeftCorner<3, 3>() = WI + WI.transpose() - VH - VH.transpose() - N;
  B.template topRightCorner<3, 3>() = TR - F;
  B.template bottomLeftCorner<3, 3>() = -TR - F;
  B.template bottomRightCorner<3, 3>().setZero();
  return B;
}

namespace detail {

/// @brief rnea_derivatives; with kJointTransforms = false, data.X_up must already hold the
/// joint transforms at q (e.g. after aba at q), and they are not recomputed.
template <bool kJointTransforms, typename S, typename Q, typename Vv, typename Aa>
[[gnu::flatten]] void rnea_derivatives_impl(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                           const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<Aa>& a) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n, "rnea_derivatives: data was made for a model of another size");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea() | DataParts::rnea_derivatives()),
                    "rnea_derivatives: data was made without its rnea and rnea_derivatives parts");
  IDMPC_CHECK_ARGUMENT(q.size() == model.n && v.size() == model.n && a.size() == model.n,
                    "rnea_derivatives: q, v, a must have size model.n");
  if constexpr (kJointTransforms) data.passes.kinematics(q);
  data.passes.mass_matrix();
  IDMPC_CHECK_ARGUMENT(!model.gravcomp || data.oIg.size() == static_cast<std::size_t>(model.n),
                       "rnea_derivatives: data was made for a model without gravity compensation");
  const int n = model.n;
  const bool gravcomp = model.gravcomp;
  const Vec6<S> a0 = base_acceleration<S>(model);
  // forward pass in the world frame: placements, axes, velocities, accelerations, forces
  for (int i = 0; i < n; ++i) {
    const int p = model.parent[i];
    if constexpr (kJointTransforms) joint_transform<S>(model, i, S(q[i]), data.X_up[i]);
    data.oX[i] = p < 0 ? data.X_up[i] : data.X_up[i] * data.oX[p];
    data.oS[i] = data.oX[i].apply_inverse_motion(motion_subspace<S>(model, i));
    const Vec6<S> vJ = data.oS[i] * v[i];
    data.oV[i] = p < 0 ? vJ : Vec6<S>(data.oV[p] + vJ);
    data.oA[i] = (p < 0 ? a0 : data.oA[p]) + data.oS[i] * a[i] + cross_motion<S>(data.oV[i], vJ);
    data.oI[i] = cast_inertia<S>(model.I[i]).transformed_to_parent(data.oX[i]);
    const Vec6<S> h = data.oI[i].apply(data.oV[i]);
    data.oF[i] = data.oI[i].apply(data.oA[i]) + cross_force<S>(data.oV[i], h);
    data.oB[i] = coriolis_matrix<S>(data.oI[i], data.oV[i], h);
    if (gravcomp) {
      data.oIg[i] = cast_inertia<S>(model.I_gravcomp[i]).transformed_to_parent(data.oX[i]);
      data.oF[i] -= data.oIg[i].apply(a0);
    }
  }
  // backward pass: composite inertias, Coriolis matrices and subtree forces
  for (int i = n - 1; i >= 0; --i) {
    const int p = model.parent[i];
    if (p >= 0) {
      data.oI[p] += data.oI[i];
      data.oB[p] += data.oB[i];
      data.oF[p] += data.oF[i];
      if (gravcomp) data.oIg[p] += data.oIg[i];
    }
  }
  // per joint: the vectors the pairwise products need
  for (int j = 0; j < n; ++j) {
    const int p = model.parent[j];
    const Vec6<S>& Sj = data.oS[j];
    const Vec6<S> vp = p < 0 ? Vec6<S>::Zero() : data.oV[p];
    const Vec6<S>& ap = p < 0 ? a0 : data.oA[p];
    data.w[j] = cross_motion<S>(Sj, vp);
    data.psi[j] = cross_motion<S>(Sj, ap) - cross_motion<S>(data.w[j], vp);
    data.IcS[j] = data.oI[j].apply(Sj);
    data.BcS[j].noalias() = data.oB[j].transpose() * Sj;
    data.G[j] = -data.oI[j].apply(data.psi[j]) - data.oB[j] * data.w[j] +
                cross_force<S>(Sj, data.oF[j]);
    data.H[j] = data.oB[j] * Sj - S(2) * data.oI[j].apply(data.w[j]);
    if (gravcomp) {
      // minus the derivatives of the compensated gravity torques, those of a model with the
      // composite inertias oIg, at rest: ψ_j becomes S_j × a0, w_j and B vanish
      data.psig[j] = cross_motion<S>(Sj, a0);
      data.IgS[j] = data.oIg[j].apply(Sj);
      data.G[j] += data.oIg[j].apply(data.psig[j]);
    }
    data.tau[j] =
        Sj.dot(data.oF[j]) + armature_and_passive<S>(model, j, S(q[j]), S(v[j]), S(a[j]));
  }
  // pairs (i, j) with j an ancestor of i or i itself, and their transposed places
  data.dtau_dq.setZero();
  data.dtau_dv.setZero();
  for (int i = 0; i < n; ++i) {
    for (int j = i; j >= 0; j = model.parent[j]) {
      data.dtau_dq(i, j) = -data.IcS[i].dot(data.psi[j]) - data.BcS[i].dot(data.w[j]);
      if (gravcomp) data.dtau_dq(i, j) += data.IgS[i].dot(data.psig[j]);
      data.dtau_dv(i, j) = data.BcS[i].dot(data.oS[j]) - S(2) * data.IcS[i].dot(data.w[j]);
      data.M(i, j) = data.M(j, i) = data.IcS[i].dot(data.oS[j]);
      if (j != i) {
        data.dtau_dq(j, i) = data.oS[j].dot(data.G[i]);
        data.dtau_dv(j, i) = data.oS[j].dot(data.H[i]);
      }
    }
    const ArmaturePassivePartials d = armature_passive_partials(model, i);
    data.dtau_dq(i, i) += d.dq;
    data.dtau_dv(i, i) += d.dv + friction_slope<S>(model, i, S(v[i]));
    data.M(i, i) += d.da;
  }
}

}  // namespace detail

/// @brief Fills data.dtau_dq, data.dtau_dv, data.M (= ∂τ/∂a) and data.tau at (q, v, a).
template <typename S, typename Q, typename Vv, typename Aa>
void rnea_derivatives(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                      const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<Aa>& a) {
  detail::rnea_derivatives_impl<true>(model, data, q, v, a);
}

}  // namespace idmpc
