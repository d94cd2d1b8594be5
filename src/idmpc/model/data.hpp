#pragma once
/// @file data.hpp
/// @brief Per-thread workspace of the dynamics algorithms. Every buffer is allocated here;
/// the algorithms never allocate.

#include <cstring>
#include <type_traits>
#include <vector>

#include "idmpc/model/checks.hpp"
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

/// @brief Groups of Data's buffers, by the algorithms that use them. A Data made with some
/// parts leaves the buffers of the others empty (no heap), so that a workspace holds what its
/// algorithms touch; calling an algorithm whose part is missing is a precondition violation,
/// checked in debug builds. M belongs to the derivatives, CRBA and LᵀDL alike; Am to the dense
/// M⁻¹ and to minv_apply_columns.
class DataParts {
 public:
  constexpr DataParts() = default;
  constexpr DataParts operator|(DataParts o) const { return DataParts(bits_ | o.bits_); }
  /// every part of o is in this
  constexpr bool has(DataParts o) const { return (bits_ & o.bits_) == o.bits_; }
  /// some part of o is in this
  constexpr bool any(DataParts o) const { return (bits_ & o.bits_) != 0; }

  static constexpr DataParts rnea() { return DataParts(1u << 0); }  ///< X_up, V, A, F, h, vJ, tau
  static constexpr DataParts aba() { return DataParts(1u << 1); }   ///< qdd, IA, pA, U, c, Ud, D, Dinv, u
  static constexpr DataParts minv_apply() { return DataParts(1u << 2); }  ///< pz, az, Minv_x, Ud_parent
  static constexpr DataParts rnea_vjp() { return DataParts(1u << 3); }    ///< fbar, abar, vbar, g_q, g_v, g_a
  /// oX … H, dtau_dq, dtau_dv, M
  static constexpr DataParts rnea_derivatives() { return DataParts(1u << 4); }
  static constexpr DataParts minv_matrix() { return DataParts(1u << 5); }  ///< Minv, oYA, oUD, oDinv, Am
  static constexpr DataParts aba_derivatives() { return DataParts(1u << 6); }  ///< da_dq, da_dv
  static constexpr DataParts crba() { return DataParts(1u << 7); }          ///< Ic, M, Fc
  static constexpr DataParts minv_columns() { return DataParts(1u << 8); }  ///< Pm, Am, Tm, Wm, rhs
  static constexpr DataParts ltdl() { return DataParts(1u << 9); }          ///< Lt, Dl, Dlinv, y_ltdl
  static constexpr DataParts all() { return DataParts((1u << 10) - 1); }

 private:
  constexpr explicit DataParts(unsigned bits) : bits_(bits) {}
  unsigned bits_ = 0;
};

template <typename S> struct DataTpl {
  template <typename T> using List = std::vector<T>;

  /// @brief Buffers of the given parts for the model's n joints (all by default).
  explicit DataTpl(const Model& model, DataParts parts = DataParts::all())
      : n(model.n), parts(parts),
        X_up(list<Transform<S>>(P::rnea())), V(list<Vec6<S>>(P::rnea())), A(list<Vec6<S>>(P::rnea())),
        F(list<Vec6<S>>(P::rnea())), h(list<Vec6<S>>(P::rnea())), vJ(list<Vec6<S>>(P::rnea())),
        tau(vec(P::rnea())), qdd(vec(P::aba())),
        IA(list<Mat6<S>>(P::aba())), pA(list<Vec6<S>>(P::aba())), U(list<Vec6<S>>(P::aba())),
        c(list<Vec6<S>>(P::aba())), Ud(list<Vec6<S>>(P::aba())), D(vec(P::aba())), Dinv(vec(P::aba())),
        u(vec(P::aba())),
        Ic(list<Inertia<S>>(P::crba())), M(mat(P::rnea_derivatives() | P::crba() | P::ltdl())),
        oX(list<Transform<S>>(P::rnea_derivatives())), oS(list<Vec6<S>>(P::rnea_derivatives())),
        oV(list<Vec6<S>>(P::rnea_derivatives())), oA(list<Vec6<S>>(P::rnea_derivatives())),
        oI(list<Inertia<S>>(P::rnea_derivatives())), oB(list<Mat6<S>>(P::rnea_derivatives())),
        oF(list<Vec6<S>>(P::rnea_derivatives())), IcS(list<Vec6<S>>(P::rnea_derivatives())),
        BcS(list<Vec6<S>>(P::rnea_derivatives())), psi(list<Vec6<S>>(P::rnea_derivatives())),
        w(list<Vec6<S>>(P::rnea_derivatives())), G(list<Vec6<S>>(P::rnea_derivatives())),
        H(list<Vec6<S>>(P::rnea_derivatives())),
        dtau_dq(mat(P::rnea_derivatives())), dtau_dv(mat(P::rnea_derivatives())),
        Minv(mat(P::minv_matrix())), da_dq(mat(P::aba_derivatives())), da_dv(mat(P::aba_derivatives())),
        fbar(list<Vec6<S>>(P::rnea_vjp())), abar(list<Vec6<S>>(P::rnea_vjp())), vbar(list<Vec6<S>>(P::rnea_vjp())),
        g_q(vec(P::rnea_vjp())), g_v(vec(P::rnea_vjp())), g_a(vec(P::rnea_vjp())),
        pz(list<Vec6<S>>(P::minv_apply())), az(list<Vec6<S>>(P::minv_apply())), Minv_x(vec(P::minv_apply())),
        oYA(list<Mat6<S>>(P::minv_matrix())), oUD(list<Vec6<S>>(P::minv_matrix())), oDinv(vec(P::minv_matrix())),
        Pm(parts.has(P::minv_columns()) ? n : 0, Block6(6, n)),
        Am(parts.any(P::minv_columns() | P::minv_matrix()) ? n : 0, Block6(6, n)),
        Tm(6, cols(P::minv_columns())), Wm(3, cols(P::minv_columns())),
        rhs(mat(P::minv_columns())), Ud_parent(list<Vec6<S>>(P::minv_apply())),
        Lt(mat(P::ltdl())), Dl(vec(P::ltdl())), Dlinv(vec(P::ltdl())), y_ltdl(vec(P::ltdl())),
        Fc(SpatialSet<S>::Zero(6, cols(P::crba()))),
        Ag(gravcomp_list<Vec6<S>>(model, P::rnea())), gbar(gravcomp_list<Vec6<S>>(model, P::rnea_vjp())),
        oIg(gravcomp_list<Inertia<S>>(model, P::rnea_derivatives())),
        IgS(gravcomp_list<Vec6<S>>(model, P::rnea_derivatives())),
        psig(gravcomp_list<Vec6<S>>(model, P::rnea_derivatives())),
        passes(n) {}

  int n;
  DataParts parts;  ///< the buffers allocated (the others are empty)

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

  // gravity compensation, allocated only for a model with model.gravcomp (after the buffers
  // above, which keep their places): Ag[i] = X_{i,0}·a0, the base acceleration −g in link i's
  // frame (rnea, aba); gbar its adjoint (rnea_vjp); oIg the compensated inertias in the world
  // frame, then composite, IgS = oIg_i·S_i and psig_j = S_j × a0 (rnea_derivatives)
  List<Vec6<S>> Ag, gbar;
  List<Inertia<S>> oIg;
  List<Vec6<S>> IgS, psig;

  /// what the buffers above hold (debug builds)
  PassRecord<S> passes;

 private:
  using P = DataParts;
  // n of a buffer in one of the parts p, else 0
  int cols(DataParts p) const { return parts.any(p) ? n : 0; }
  template <typename T> List<T> list(DataParts p) const { return List<T>(static_cast<size_t>(cols(p))); }
  template <typename T> List<T> gravcomp_list(const Model& model, DataParts p) const {
    return model.gravcomp ? list<T>(p) : List<T>();
  }
  VecX<S> vec(DataParts p) const { return VecX<S>::Zero(cols(p)); }
  MatX<S> mat(DataParts p) const { return MatX<S>::Zero(cols(p), cols(p)); }
};

/// @brief Bytes of heap a workspace owns: every buffer's elements (fixed-size elements of the
/// lists inline, the 6×n blocks' own heap added), without the allocator's bookkeeping.
template <typename S> std::size_t heap_bytes(const DataTpl<S>& d) {
  std::size_t b = 0;
  const auto add = [&b](const auto& x) {
    using X = std::decay_t<decltype(x)>;
    if constexpr (std::is_base_of_v<Eigen::PlainObjectBase<X>, X>) {
      b += static_cast<std::size_t>(x.size()) * sizeof(typename X::Scalar);
    } else {
      b += x.capacity() * sizeof(typename X::value_type);
      if constexpr (std::is_base_of_v<Eigen::PlainObjectBase<typename X::value_type>, typename X::value_type>) {
        if constexpr (X::value_type::SizeAtCompileTime == Eigen::Dynamic) {
          for (const auto& e : x) b += static_cast<std::size_t>(e.size()) * sizeof(S);
        }
      }
    }
  };
  const auto all = [&add](const auto&... x) { (add(x), ...); };
  all(d.X_up, d.V, d.A, d.F, d.h, d.vJ, d.tau, d.qdd, d.IA, d.pA, d.U, d.c, d.Ud, d.D, d.Dinv, d.u, d.Ic, d.M,
      d.oX, d.oS, d.oV, d.oA, d.oI, d.oB, d.oF, d.IcS, d.BcS, d.psi, d.w, d.G, d.H, d.dtau_dq, d.dtau_dv, d.Minv,
      d.da_dq, d.da_dv, d.fbar, d.abar, d.vbar, d.g_q, d.g_v, d.g_a, d.pz, d.az, d.Minv_x, d.oYA, d.oUD, d.oDinv,
      d.Pm, d.Am, d.Tm, d.Wm, d.rhs, d.Ud_parent, d.Lt, d.Dl, d.Dlinv, d.y_ltdl, d.Fc, d.Ag, d.gbar,
      d.oIg, d.IgS, d.psig);
  return b + 4 * static_cast<std::size_t>(d.n) * sizeof(S);  // the pass record's four points
}

using Data = DataTpl<double>;

}  // namespace idmpc
