#pragma once
/// @file data.hpp
/// @brief Per-thread workspace of the dynamics algorithms. Every buffer is allocated here;
/// the algorithms never allocate.

#include <vector>

#include "idmpc/model/model.hpp"

namespace idmpc {

template <typename S> struct DataTpl {
  template <typename T> using List = std::vector<T>;

  explicit DataTpl(const Model& model)
      : n(model.n),
        X_up(n), V(n), A(n), F(n), h(n), vJ(n),
        tau(VecX<S>::Zero(n)), qdd(VecX<S>::Zero(n)),
        IA(n), pA(n), U(n), c(n), D(VecX<S>::Zero(n)), u(VecX<S>::Zero(n)),
        Ic(n), M(MatX<S>::Zero(n, n)),
        oX(n), oS(n), oV(n), oA(n), oI(n), oB(n), oF(n), IcS(n), BcS(n), psi(n), w(n), G(n), H(n),
        dtau_dq(MatX<S>::Zero(n, n)), dtau_dv(MatX<S>::Zero(n, n)),
        Minv(MatX<S>::Zero(n, n)), da_dq(MatX<S>::Zero(n, n)),
        da_dv(MatX<S>::Zero(n, n)),
        fbar(n), abar(n), vbar(n),
        g_q(VecX<S>::Zero(n)), g_v(VecX<S>::Zero(n)), g_a(VecX<S>::Zero(n)),
        pz(n), az(n), Minv_x(VecX<S>::Zero(n)),
        Pm(n, Block6(6, n)), Am(n, Block6(6, n)), Tm(6, n), Wm(3, n),
        rhs(MatX<S>::Zero(n, n)) {}

  int n;

  // kinematics and RNEA (link frames): X_up[i] = XJ(q_i)·X_tree[i]; V, A body velocity and
  // acceleration (A includes −gravity); F body force, then subtree force after the backward
  // pass; h = I·V; vJ = S·v
  List<Transform<S>> X_up;
  List<Vec6<S>> V, A, F, h, vJ;
  VecX<S> tau;  ///< rnea output
  VecX<S> qdd;  ///< aba output

  // ABA (Featherstone Table 7.1)
  List<Mat6<S>> IA;
  List<Vec6<S>> pA, U, c;
  VecX<S> D, u;

  // CRBA
  List<Inertia<S>> Ic;
  MatX<S> M;

  // RNEA derivatives (world frame): placements, subspaces, velocities, accelerations, composite
  // inertias and composite Coriolis matrices B, subtree forces; per-joint helper vectors
  List<Transform<S>> oX;
  List<Vec6<S>> oS, oV, oA;
  List<Inertia<S>> oI;
  List<Mat6<S>> oB;
  List<Vec6<S>> oF, IcS, BcS, psi, w, G, H;
  MatX<S> dtau_dq, dtau_dv;

  // forward-dynamics derivatives
  MatX<S> Minv;
  MatX<S> da_dq, da_dv;

  // RNEA vector–Jacobian products: adjoints of body force, acceleration, velocity
  List<Vec6<S>> fbar, abar, vbar;
  VecX<S> g_q, g_v, g_a;  ///< (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M·w

  // M⁻¹x through the ABA factorization
  List<Vec6<S>> pz, az;
  VecX<S> Minv_x;

  // M⁻¹X for up to n right-hand sides at once (minv_apply_columns)
  using Block6 = Eigen::Matrix<S, 6, Eigen::Dynamic>;
  List<Block6> Pm, Am;
  Block6 Tm;
  Eigen::Matrix<S, 3, Eigen::Dynamic> Wm;
  MatX<S> rhs;
};

using Data = DataTpl<double>;

}  // namespace idmpc
