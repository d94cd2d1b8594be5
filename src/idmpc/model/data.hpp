#pragma once
/// @file data.hpp
/// @brief Per-thread workspace of the dynamics algorithms. Every buffer is allocated here;
/// the algorithms never allocate.

#include <cstring>
#include <vector>

#include "idmpc/model/debug_check.hpp"
#include "idmpc/model/model.hpp"

namespace idmpc {

/// @brief Which algorithm's results a Data holds, for the debug checks of the call-order
/// preconditions (rnea_vjp after rnea or rnea_after_aba; minv_apply, minv_apply_columns and
/// aba_derivatives_after_aba after aba, at the same point; ltdl_factor after M was computed,
/// ltdl_solve after ltdl_factor). Written and read only when
/// IDMPC_DEBUG_CHECKS; always present, so that Data's layout does not depend on the build type.
template <typename S> class PassRecord {
 public:
  explicit PassRecord(int n)
      : X_up_q_(VecX<S>::Zero(n)), rnea_q_(VecX<S>::Zero(n)), aba_q_(VecX<S>::Zero(n)),
        aba_v_(VecX<S>::Zero(n)) {}

  /// X_up was computed at q
  template <typename Q> void kinematics(const Eigen::MatrixBase<Q>& q) {
    if constexpr (kOn) X_up_q_ = q;
  }
  /// rnea(q, ·, ·) filled X_up, V, A, F, h, vJ
  template <typename Q> void rnea(const Eigen::MatrixBase<Q>& q) {
    if constexpr (kOn) {
      kinematics(q);
      rnea_q_ = q;
      rnea_ = true;
    }
  }
  /// aba(q, v, ·) filled X_up, IA, U, D, qdd and overwrote rnea's V, A, vJ
  template <typename Q, typename V>
  void aba(const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v) {
    if constexpr (kOn) {
      kinematics(q);
      aba_q_ = q;
      aba_v_ = v;
      aba_ = true;
      rnea_ = false;
    }
  }

  /// rnea_after_aba completed rnea's buffers at the point of the aba pass (aba's stay valid)
  void rnea_after_aba() {
    if constexpr (kOn) {
      rnea_q_ = aba_q_;
      rnea_ = true;
    }
  }

  /// data.M was computed (crba or rnea_derivatives); nothing else writes it
  void mass_matrix() {
    if constexpr (kOn) mass_matrix_ = true;
  }
  /// ltdl_factor factored data.M into Lt, Dl (nothing else writes them)
  void ltdl() {
    if constexpr (kOn) ltdl_ = true;
  }
  bool holds_mass_matrix() const { return mass_matrix_; }
  bool holds_ltdl() const { return ltdl_; }

  /// the buffers hold an rnea pass whose X_up is still in place
  bool holds_rnea() const { return rnea_ && same(rnea_q_, X_up_q_); }
  /// the buffers hold an aba factorization whose X_up is still in place
  bool holds_aba() const { return aba_ && same(aba_q_, X_up_q_); }
  /// … and it was made at (q, v)
  template <typename Q, typename V>
  bool holds_aba_at(const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v) const {
    return holds_aba() && same(aba_q_, q) && same(aba_v_, v);
  }

 private:
  static constexpr bool kOn = IDMPC_DEBUG_CHECKS != 0;

  // bitwise equality: the same point is the same numbers (S may be a SIMD pack)
  template <typename X> static bool same(const VecX<S>& a, const Eigen::MatrixBase<X>& b) {
    if (a.size() != b.size()) return false;
    for (Eigen::Index i = 0; i < a.size(); ++i) {
      const S bi = b[i];
      if (std::memcmp(&a[i], &bi, sizeof(S)) != 0) return false;
    }
    return true;
  }

  VecX<S> X_up_q_, rnea_q_, aba_q_, aba_v_;
  bool rnea_ = false, aba_ = false, mass_matrix_ = false, ltdl_ = false;
};

template <typename S> struct DataTpl {
  template <typename T> using List = std::vector<T>;

  explicit DataTpl(const Model& model)
      : n(model.n),
        X_up(n), V(n), A(n), F(n), h(n), vJ(n),
        tau(VecX<S>::Zero(n)), qdd(VecX<S>::Zero(n)),
        IA(n), pA(n), U(n), c(n), Ud(n), D(VecX<S>::Zero(n)), Dinv(VecX<S>::Zero(n)),
        u(VecX<S>::Zero(n)),
        Ic(n), M(MatX<S>::Zero(n, n)),
        oX(n), oS(n), oV(n), oA(n), oI(n), oB(n), oF(n), IcS(n), BcS(n), psi(n), w(n), G(n), H(n),
        dtau_dq(MatX<S>::Zero(n, n)), dtau_dv(MatX<S>::Zero(n, n)),
        Minv(MatX<S>::Zero(n, n)), da_dq(MatX<S>::Zero(n, n)),
        da_dv(MatX<S>::Zero(n, n)),
        fbar(n), abar(n), vbar(n),
        g_q(VecX<S>::Zero(n)), g_v(VecX<S>::Zero(n)), g_a(VecX<S>::Zero(n)),
        pz(n), az(n), Minv_x(VecX<S>::Zero(n)), oYA(n), oUD(n), oDinv(VecX<S>::Zero(n)),
        Pm(n, Block6(6, n)), Am(n, Block6(6, n)), Tm(6, n), Wm(3, n),
        rhs(MatX<S>::Zero(n, n)), Ud_parent(n),
        Lt(MatX<S>::Zero(n, n)), Dl(VecX<S>::Zero(n)), Dlinv(VecX<S>::Zero(n)),
        y_ltdl(VecX<S>::Zero(n)),
        Fc(SpatialSet<S>::Zero(6, n)),
        passes(n) {}

  int n;

  // kinematics and RNEA (link frames): X_up[i] = XJ(q_i)·X_tree[i]; V, A body velocity and
  // acceleration (A includes −gravity); F body force, then subtree force after the backward
  // pass; h = I·V; vJ = S·v
  List<Transform<S>> X_up;
  List<Vec6<S>> V, A, F, h, vJ;
  VecX<S> tau;  ///< rnea output
  VecX<S> qdd;  ///< aba output

  // ABA (Featherstone Table 7.1); Ud = U/D and Dinv = 1/D for the sweeps of the dense M⁻¹
  List<Mat6<S>> IA;
  List<Vec6<S>> pA, U, c, Ud;
  VecX<S> D, Dinv, u;

  // CRBA (and its force set Fc, last)
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

  // M⁻¹x through the ABA factorization (and Ud_parent, last)
  List<Vec6<S>> pz, az;
  VecX<S> Minv_x;
  // dense M⁻¹ (minv.hpp): articulated inertias, U/D and 1/D in the world frame
  List<Mat6<S>> oYA;
  List<Vec6<S>> oUD;
  VecX<S> oDinv;

  // M⁻¹X for up to n right-hand sides at once (minv_apply_columns)
  using Block6 = Eigen::Matrix<S, 6, Eigen::Dynamic>;
  List<Block6> Pm, Am;
  Block6 Tm;
  Eigen::Matrix<S, 3, Eigen::Dynamic> Wm;
  MatX<S> rhs;
  /// U/D in the parent's frame, X_upᵀ·Ud (minv_apply). Allocated after the buffers above:
  /// constructed between az and Minv_x, it moved the heap blocks of the n×n buffers after it,
  /// and FD matrix at n = 64 took 1.3–1.6× the time per update (their cache-set placement,
  /// not their arithmetic).
  List<Vec6<S>> Ud_parent;

  // sparse LᵀDL factor of M (ltdl.hpp), after the buffers above so as not to move them: column
  // k of Lt holds row k of L at k's ancestors; D, 1/D; the solve's output
  MatX<S> Lt;
  VecX<S> Dl, Dlinv, y_ltdl;

  // CRBA's force set: column t holds Ic_j·S_j of link j = model.preorder[t] (crba.hpp)
  SpatialSet<S> Fc;

  /// what the buffers above hold (debug builds)
  PassRecord<S> passes;
};

using Data = DataTpl<double>;

}  // namespace idmpc
