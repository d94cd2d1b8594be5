#pragma once
/// @file pack.hpp
/// @brief Pack<W>: W doubles operated on together (GCC vector extension), usable as the scalar
/// of the templated dynamics, so that one RNEA evaluates W horizon stages in SIMD lanes.
///
/// Only arithmetic, sin/cos, sqrt and tanh are provided: enough for RNEA, ABA and their adjoints;
/// comparisons (pivoting, norms) are deliberately absent.

#include <cmath>

#include <Eigen/Core>

namespace idmpc {

namespace detail {
// GCC vector types of W doubles; alignment lowered to 8 so that any Eigen storage is valid
template <int W> struct PackVec;
template <> struct PackVec<2> { typedef double type __attribute__((vector_size(16), aligned(8))); };
template <> struct PackVec<4> { typedef double type __attribute__((vector_size(32), aligned(8))); };
template <> struct PackVec<8> { typedef double type __attribute__((vector_size(64), aligned(8))); };
}  // namespace detail

template <int W> struct Pack {
  using Vec = typename detail::PackVec<W>::type;
  Vec v;

  Pack() = default;
  Pack(double x) { for (int k = 0; k < W; ++k) v[k] = x; }  // NOLINT: broadcast, as a scalar
  Pack(int x) : Pack(static_cast<double>(x)) {}               // NOLINT
  static Pack from(const Vec& x) {
    Pack p;
    p.v = x;
    return p;
  }
  double operator[](int k) const { return v[k]; }
  double& operator[](int k) { return reinterpret_cast<double*>(&v)[k]; }

  Pack& operator+=(const Pack& o) { v += o.v; return *this; }
  Pack& operator-=(const Pack& o) { v -= o.v; return *this; }
  Pack& operator*=(const Pack& o) { v *= o.v; return *this; }
  Pack& operator/=(const Pack& o) { v /= o.v; return *this; }
  friend Pack operator+(const Pack& a, const Pack& b) { return from(a.v + b.v); }
  friend Pack operator-(const Pack& a, const Pack& b) { return from(a.v - b.v); }
  friend Pack operator*(const Pack& a, const Pack& b) { return from(a.v * b.v); }
  friend Pack operator/(const Pack& a, const Pack& b) { return from(a.v / b.v); }
  friend Pack operator-(const Pack& a) { return from(-a.v); }
  friend Pack operator*(double a, const Pack& b) { return from(a * b.v); }
  friend Pack operator*(const Pack& a, double b) { return from(a.v * b); }
  friend Pack operator+(double a, const Pack& b) { return from(a + b.v); }
  friend Pack operator+(const Pack& a, double b) { return from(a.v + b); }
  friend Pack operator-(double a, const Pack& b) { return from(a - b.v); }
  friend Pack operator-(const Pack& a, double b) { return from(a.v - b); }

  friend Pack sin(const Pack& a) {
    Pack r;
    for (int k = 0; k < W; ++k) r.v[k] = std::sin(a.v[k]);
    return r;
  }
  friend Pack cos(const Pack& a) {
    Pack r;
    for (int k = 0; k < W; ++k) r.v[k] = std::cos(a.v[k]);
    return r;
  }
  friend Pack sqrt(const Pack& a) {
    Pack r;
    for (int k = 0; k < W; ++k) r.v[k] = std::sqrt(a.v[k]);
    return r;
  }
  friend Pack tanh(const Pack& a) {
    Pack r;
    for (int k = 0; k < W; ++k) r.v[k] = std::tanh(a.v[k]);
    return r;
  }
};

/// @brief Stages evaluated together: 4 doubles (one AVX2 register, two SSE2 registers).
inline constexpr int kStageLanes = 4;
using StagePack = Pack<kStageLanes>;

}  // namespace idmpc

namespace Eigen {

template <int W> struct NumTraits<idmpc::Pack<W>> : GenericNumTraits<double> {
  using Real = idmpc::Pack<W>;
  using NonInteger = idmpc::Pack<W>;
  using Nested = idmpc::Pack<W>;
  using Literal = idmpc::Pack<W>;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 0,
    ReadCost = 1,
    AddCost = W,
    MulCost = W
  };
};

}  // namespace Eigen
