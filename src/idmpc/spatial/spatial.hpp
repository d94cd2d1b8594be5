#pragma once
/// @file spatial.hpp
/// @brief Spatial algebra (Featherstone 2008, ch. 2), angular-first: a motion is [ω; v], a
/// force is [n; f], both expressed at the origin of the frame they are written in.
///
/// Fixed-size types only; no 6×6 products are formed by the algorithms that use these helpers.

#include <type_traits>

#include <Eigen/Core>
#include <Eigen/Geometry>

/// Before a loop over arrays the compiler cannot prove disjoint (rows of one matrix): lets gcc
/// vectorize it without a run-time overlap check. Empty elsewhere: clang's counterpart
/// (vectorize(assume_safety)) fails the build with -Werror where it cannot vectorize, e.g.
/// under the sanitizers, and clang checks the overlap at run time by itself.
#if defined(__GNUC__) && !defined(__clang__)
#define IDMPC_IVDEP _Pragma("GCC ivdep")
#else
#define IDMPC_IVDEP
#endif

namespace idmpc {

template <typename S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <typename S> using Mat3 = Eigen::Matrix<S, 3, 3>;
template <typename S> using Vec6 = Eigen::Matrix<S, 6, 1>;
template <typename S> using Mat6 = Eigen::Matrix<S, 6, 6>;
template <typename S> using VecX = Eigen::Matrix<S, Eigen::Dynamic, 1>;
template <typename S> using MatX = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
/// A set of spatial vectors as the columns of a 6×k matrix stored row by row: each component is
/// contiguous across the set, so that one transform applies to all of them in vector loops.
template <typename S> using SpatialSet = Eigen::Matrix<S, 6, Eigen::Dynamic, Eigen::RowMajor>;

/// @brief Skew-symmetric matrix [x]× with [x]× y = x × y.
template <typename S> Mat3<S> skew(const Vec3<S>& x) {
  Mat3<S> m;
  m << S(0), -x.z(), x.y(), x.z(), S(0), -x.x(), -x.y(), x.x(), S(0);
  return m;
}

/// @brief 3-D cross product written out (Eigen's generic version shuffles SSE registers).
template <typename S, typename A, typename B>
inline Vec3<S> cross3(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  return Vec3<S>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}

/// @brief Motion cross product m1 × m2 (Featherstone eq. 2.31).
template <typename S> Vec6<S> cross_motion(const Vec6<S>& m1, const Vec6<S>& m2) {
  const auto w1 = m1.template head<3>(), v1 = m1.template tail<3>();
  const auto w2 = m2.template head<3>(), v2 = m2.template tail<3>();
  Vec6<S> r;
  r.template head<3>() = cross3<S>(w1, w2);
  r.template tail<3>() = cross3<S>(w1, v2) + cross3<S>(v1, w2);
  return r;
}

/// @brief Force cross product m ×* f (Featherstone eq. 2.32).
template <typename S> Vec6<S> cross_force(const Vec6<S>& m, const Vec6<S>& f) {
  const auto w = m.template head<3>(), v = m.template tail<3>();
  const auto n = f.template head<3>(), fl = f.template tail<3>();
  Vec6<S> r;
  r.template head<3>() = cross3<S>(w, n) + cross3<S>(v, fl);
  r.template tail<3>() = cross3<S>(w, fl);
  return r;
}

/// @brief 6×6 matrix of m× (motion cross operator).
template <typename S> Mat6<S> cross_motion_matrix(const Vec6<S>& m) {
  Mat6<S> X = Mat6<S>::Zero();
  const Mat3<S> W = skew<S>(m.template head<3>());
  X.template topLeftCorner<3, 3>() = W;
  X.template bottomRightCorner<3, 3>() = W;
  X.template bottomLeftCorner<3, 3>() = skew<S>(m.template tail<3>());
  return X;
}

/// @brief 6×6 matrix of m×* (force cross operator) = −(m×)ᵀ.
template <typename S> Mat6<S> cross_force_matrix(const Vec6<S>& m) {
  Mat6<S> X = Mat6<S>::Zero();
  const Mat3<S> W = skew<S>(m.template head<3>());
  X.template topLeftCorner<3, 3>() = W;
  X.template bottomRightCorner<3, 3>() = W;
  X.template topRightCorner<3, 3>() = skew<S>(m.template tail<3>());
  return X;
}

/// @brief 6×6 matrix B(f) with B(f) m = m ×* f, linear in the motion m.
template <typename S> Mat6<S> cross_force_bar_matrix(const Vec6<S>& f) {
  Mat6<S> X = Mat6<S>::Zero();
  const Mat3<S> N = skew<S>(f.template head<3>());
  const Mat3<S> F = skew<S>(f.template tail<3>());
  X.template topLeftCorner<3, 3>() = -N;
  X.template topRightCorner<3, 3>() = -F;
  X.template bottomLeftCorner<3, 3>() = -F;
  return X;
}

/// @brief Plücker transform ^B X_A from frame A to frame B, stored as (E, r): E rotates
/// A-coordinates into B-coordinates and r is B's origin in A-coordinates.
template <typename S> struct Transform {
  Mat3<S> E = Mat3<S>::Identity();
  Vec3<S> r = Vec3<S>::Zero();

  static Transform identity() { return Transform{}; }

  /// @brief X m: motion from A to B coordinates.
  Vec6<S> apply_motion(const Vec6<S>& m) const {
    Vec6<S> out;
    const auto w = m.template head<3>();
    out.template head<3>() = E * w;
    out.template tail<3>() = E * (m.template tail<3>() - cross3<S>(r, w));
    return out;
  }
  /// @brief X⁻¹ m: motion from B to A coordinates.
  Vec6<S> apply_inverse_motion(const Vec6<S>& m) const {
    Vec6<S> out;
    const Vec3<S> w = E.transpose() * m.template head<3>();
    out.template head<3>() = w;
    out.template tail<3>() = E.transpose() * m.template tail<3>() + cross3<S>(r, w);
    return out;
  }
  /// @brief X* f: force from A to B coordinates.
  Vec6<S> apply_force(const Vec6<S>& f) const {
    Vec6<S> out;
    const auto fl = f.template tail<3>();
    out.template head<3>() = E * (f.template head<3>() - cross3<S>(r, fl));
    out.template tail<3>() = E * fl;
    return out;
  }
  /// @brief Xᵀ f: force from B back to A coordinates (= (X*)⁻¹ f).
  Vec6<S> apply_transpose_force(const Vec6<S>& f) const {
    Vec6<S> out;
    const Vec3<S> fl = E.transpose() * f.template tail<3>();
    out.template head<3>() = E.transpose() * f.template head<3>() + cross3<S>(r, fl);
    out.template tail<3>() = fl;
    return out;
  }
  /// @brief Xᵀ f for each force f in the columns [b, e) of F, in place.
  void apply_transpose_force_to_columns(SpatialSet<S>& F, int b, int e) const {
    const S e00 = E(0, 0), e01 = E(0, 1), e02 = E(0, 2), e10 = E(1, 0), e11 = E(1, 1),
            e12 = E(1, 2), e20 = E(2, 0), e21 = E(2, 1), e22 = E(2, 2);
    const S r0 = r[0], r1 = r[1], r2 = r[2];
    S* n0 = F.row(0).data();
    S* n1 = F.row(1).data();
    S* n2 = F.row(2).data();
    S* f0 = F.row(3).data();
    S* f1 = F.row(4).data();
    S* f2 = F.row(5).data();
    IDMPC_IVDEP
    for (int t = b; t < e; ++t) {
      const S g0 = e00 * f0[t] + e10 * f1[t] + e20 * f2[t];
      const S g1 = e01 * f0[t] + e11 * f1[t] + e21 * f2[t];
      const S g2 = e02 * f0[t] + e12 * f1[t] + e22 * f2[t];
      const S m0 = e00 * n0[t] + e10 * n1[t] + e20 * n2[t];
      const S m1 = e01 * n0[t] + e11 * n1[t] + e21 * n2[t];
      const S m2 = e02 * n0[t] + e12 * n1[t] + e22 * n2[t];
      n0[t] = m0 + r1 * g2 - r2 * g1;
      n1[t] = m1 + r2 * g0 - r0 * g2;
      n2[t] = m2 + r0 * g1 - r1 * g0;
      f0[t] = g0;
      f1[t] = g1;
      f2[t] = g2;
    }
  }
  /// @brief Composition (this ∘ other): first `other` (A→B), then this (B→C); gives A→C.
  Transform operator*(const Transform& other) const {
    Transform out;
    out.E = E * other.E;
    out.r = other.r + other.E.transpose() * r;
    return out;
  }
  /// @brief Inverse transform (B→A).
  Transform inverse() const {
    Transform out;
    out.E = E.transpose();
    out.r = -(E * r);
    return out;
  }
  /// @brief Dense 6×6 motion transform (for tests and reference code only).
  Mat6<S> motion_matrix() const {
    Mat6<S> X = Mat6<S>::Zero();
    X.template topLeftCorner<3, 3>() = E;
    X.template bottomRightCorner<3, 3>() = E;
    X.template bottomLeftCorner<3, 3>() = -E * skew<S>(r);
    return X;
  }
};

/// @brief Spatial inertia of a rigid body about a frame origin: mass m, first moment
/// h = m·c (c: centre of mass) and rotational inertia Ibar about the origin.
template <typename S> struct Inertia {
  S m = S(0);
  Vec3<S> h = Vec3<S>::Zero();
  Mat3<S> Ibar = Mat3<S>::Zero();

  /// @brief From mass, centre of mass and rotational inertia about the centre of mass.
  static Inertia from_com(S mass, const Vec3<S>& com, const Mat3<S>& I_com) {
    Inertia out;
    out.m = mass;
    out.h = mass * com;
    const Mat3<S> C = skew<S>(com);
    out.Ibar = I_com - mass * C * C;
    return out;
  }
  /// @brief I m (a force).
  Vec6<S> apply(const Vec6<S>& mo) const {
    const auto w = mo.template head<3>(), v = mo.template tail<3>();
    Vec6<S> out;
    out.template head<3>() = Ibar * w + cross3<S>(h, v);
    out.template tail<3>() = m * v - cross3<S>(h, w);
    return out;
  }
  Inertia& operator+=(const Inertia& o) {
    m += o.m;
    h += o.h;
    Ibar += o.Ibar;
    return *this;
  }
  /// @brief Re-express an inertia given in B-coordinates (X: A→B) in A-coordinates: Xᵀ I X.
  ///
  /// Ibar' = Eᵀ Ibar E − [y]×[r]× − [r]×[y]× − m [r]×[r]× with y = Eᵀh; by
  /// [a]×[b]× = b aᵀ − (a·b) 1 the translation part is 2 (g·r) 1 − r gᵀ − g rᵀ, g = y + m r / 2.
  /// Only the upper triangle is computed (Ibar is symmetric): 45 + 18 multiplications.
  Inertia transformed_to_parent(const Transform<S>& X) const {
    Inertia out;
    out.m = S(0);
    add_transformed_to_parent(X, out);
    return out;
  }
  /// @brief out += transformed_to_parent(X), without the intermediate inertia.
  void add_transformed_to_parent(const Transform<S>& X, Inertia& out) const {
    out.m += m;
    const Mat3<S>& E = X.E;
    const Vec3<S>& r = X.r;
    const Vec3<S> y = E.transpose() * h;
    out.h += y + m * r;
    const Vec3<S> g = y + (S(0.5) * m) * r;
    const S gr2 = S(2) * g.dot(r);
    const Mat3<S> T = Ibar * E;  // Eᵀ Ibar E = Eᵀ T
    for (int a = 0; a < 3; ++a) {
      for (int b = a; b < 3; ++b) {
        S x = E(0, a) * T(0, b) + E(1, a) * T(1, b) + E(2, a) * T(2, b) - r[a] * g[b] - g[a] * r[b];
        if (a == b) x += gr2;
        out.Ibar(a, b) += x;
        if (b != a) out.Ibar(b, a) += x;
      }
    }
  }
  /// @brief Dense 6×6 matrix.
  Mat6<S> matrix() const {
    Mat6<S> M;
    const Mat3<S> H = skew<S>(h);
    M.template topLeftCorner<3, 3>() = Ibar;
    M.template topRightCorner<3, 3>() = H;
    M.template bottomLeftCorner<3, 3>() = -H;
    M.template bottomRightCorner<3, 3>() = m * Mat3<S>::Identity();
    return M;
  }
};

/// @brief Xᵀ·IA·X for a symmetric 6×6 inertia IA given in B-coordinates (X: A→B), computed
/// with 3×3 blocks: the articulated inertia of a child expressed in its parent's frame.
template <typename S> Mat6<S> congruence_to_parent(const Mat6<S>& IA, const Transform<S>& X) {
  // rotate: blocks of diag(Eᵀ,Eᵀ)·IA·diag(E,E)
  const Mat3<S> A = X.E.transpose() * IA.template topLeftCorner<3, 3>() * X.E;
  const Mat3<S> B = X.E.transpose() * IA.template topRightCorner<3, 3>() * X.E;
  const Mat3<S> C = X.E.transpose() * IA.template bottomRightCorner<3, 3>() * X.E;
  // translate by r
  const Mat3<S> R = skew<S>(X.r);
  const Mat3<S> RC = R * C;
  Mat6<S> out;
  const Mat3<S> B2 = B + RC;
  out.template topLeftCorner<3, 3>() = A - B * R + R * B.transpose() - RC * R;
  out.template topRightCorner<3, 3>() = B2;
  out.template bottomLeftCorner<3, 3>() = B2.transpose();
  out.template bottomRightCorner<3, 3>() = C;
  return out;
}

/// @brief A model inertia (double) in scalar type S; a reference when S is double.
template <typename S>
auto cast_inertia(const Inertia<double>& I)
    -> std::conditional_t<std::is_same_v<S, double>, const Inertia<double>&, Inertia<S>> {
  if constexpr (std::is_same_v<S, double>) {
    return I;
  } else {
    Inertia<S> out;
    out.m = S(I.m);
    out.h = I.h.template cast<S>();
    out.Ibar = I.Ibar.template cast<S>();
    return out;
  }
}

/// @brief Rotation matrix of angle θ about the unit axis s (Rodrigues).
template <typename S> Mat3<S> axis_rotation(const Vec3<S>& s, S theta) {
  using std::cos;
  using std::sin;
  const S c = cos(theta), sn = sin(theta), t = S(1) - c;
  Mat3<S> R;
  R << t * s.x() * s.x() + c, t * s.x() * s.y() - sn * s.z(), t * s.x() * s.z() + sn * s.y(),
      t * s.x() * s.y() + sn * s.z(), t * s.y() * s.y() + c, t * s.y() * s.z() - sn * s.x(),
      t * s.x() * s.z() - sn * s.y(), t * s.y() * s.z() + sn * s.x(), t * s.z() * s.z() + c;
  return R;
}

}  // namespace idmpc
