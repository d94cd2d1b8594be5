#pragma once
/// @file dual.hpp
/// @brief Dual numbers x + ε·dx with ε² = 0 (forward-mode differentiation): a function
/// evaluated at x + ε·w, every operation carried out on both parts, gives f(x) + ε·f'(x)·w, the
/// directional derivative exact up to rounding, with no increment to choose. Usable, as Pack, as
/// the scalar of the templated dynamics and of the problem's stage computations (formulations.md §Exact products):
/// the exact products F'(U)·W of C/GMRES.
///
/// Only arithmetic, sin/cos, sqrt, tanh and equality (of both parts; Eigen's products ask for it)
/// are provided: what the dynamics and the costs use. Ordering comparisons are deliberately
/// absent, so that no code can branch on a dual number's value and silently drop its tangent.

#include <cmath>

#include <Eigen/Core>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

struct Dual {
  double x;   ///< value
  double dx;  ///< tangent: the derivative in the seeded direction

  Dual() = default;
  constexpr Dual(double value) : x(value), dx(0) {}  // NOLINT: a constant, as a scalar
  constexpr Dual(int value) : x(value), dx(0) {}     // NOLINT
  constexpr Dual(double value, double tangent) : x(value), dx(tangent) {}

  Dual& operator+=(const Dual& o) { x += o.x; dx += o.dx; return *this; }
  Dual& operator-=(const Dual& o) { x -= o.x; dx -= o.dx; return *this; }
  Dual& operator*=(const Dual& o) { *this = *this * o; return *this; }
  Dual& operator/=(const Dual& o) { *this = *this / o; return *this; }

  friend Dual operator+(const Dual& a, const Dual& b) { return {a.x + b.x, a.dx + b.dx}; }
  friend Dual operator-(const Dual& a, const Dual& b) { return {a.x - b.x, a.dx - b.dx}; }
  friend Dual operator*(const Dual& a, const Dual& b) { return {a.x * b.x, a.dx * b.x + a.x * b.dx}; }
  friend Dual operator/(const Dual& a, const Dual& b) {
    const double r = 1.0 / b.x, q = a.x * r;
    return {q, (a.dx - q * b.dx) * r};
  }
  friend Dual operator-(const Dual& a) { return {-a.x, -a.dx}; }
  friend Dual operator+(double a, const Dual& b) { return {a + b.x, b.dx}; }
  friend Dual operator+(const Dual& a, double b) { return {a.x + b, a.dx}; }
  friend Dual operator-(double a, const Dual& b) { return {a - b.x, -b.dx}; }
  friend Dual operator-(const Dual& a, double b) { return {a.x - b, a.dx}; }
  friend Dual operator*(double a, const Dual& b) { return {a * b.x, a * b.dx}; }
  friend Dual operator*(const Dual& a, double b) { return {a.x * b, a.dx * b}; }
  friend Dual operator/(const Dual& a, double b) { return {a.x / b, a.dx / b}; }

  friend bool operator==(const Dual& a, const Dual& b) { return a.x == b.x && a.dx == b.dx; }
  friend bool operator!=(const Dual& a, const Dual& b) { return !(a == b); }

  friend Dual sin(const Dual& a) { return {std::sin(a.x), std::cos(a.x) * a.dx}; }
  friend Dual cos(const Dual& a) { return {std::cos(a.x), -std::sin(a.x) * a.dx}; }
  friend Dual sqrt(const Dual& a) {
    const double s = std::sqrt(a.x);
    return {s, a.dx / (2 * s)};
  }
  friend Dual tanh(const Dual& a) {
    const double t = std::tanh(a.x);
    return {t, (1 - t * t) * a.dx};
  }
};

}  // namespace idmpc

namespace Eigen {

template <> struct NumTraits<idmpc::Dual> : GenericNumTraits<double> {
  using Real = idmpc::Dual;
  using NonInteger = idmpc::Dual;
  using Nested = idmpc::Dual;
  using Literal = idmpc::Dual;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 0,
    ReadCost = 1,
    AddCost = 2,
    MulCost = 3
  };
};

/// A dual number and a double combine into a dual number (the double a constant).
template <typename Op> struct ScalarBinaryOpTraits<idmpc::Dual, double, Op> { using ReturnType = idmpc::Dual; };
template <typename Op> struct ScalarBinaryOpTraits<double, idmpc::Dual, Op> { using ReturnType = idmpc::Dual; };

}  // namespace Eigen

namespace idmpc {

/// @brief x + ε·w, entry by entry (w of the size of x).
template <typename A, typename B> VecX<Dual> seeded(const Eigen::MatrixBase<A>& x, const Eigen::MatrixBase<B>& w) {
  VecX<Dual> out(x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) out[k] = Dual(x[k], w[k]);
  return out;
}

}  // namespace idmpc
