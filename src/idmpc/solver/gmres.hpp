#pragma once
/// @file gmres.hpp
/// @brief Matrix-free GMRES (Kelley 1995, Alg. 3.5.1): kmax Arnoldi steps from an initial
/// guess, modified Gram–Schmidt, Givens rotations, no restart. All storage preallocated.

#include <cmath>
#include <stdexcept>
#include <string>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

class Gmres {
 public:
  /// the Krylov basis V may hold at most this many doubles (1 GiB)
  static constexpr long long kMaxBasisEntries = 1LL << 27;

  /// @throws std::invalid_argument if dim < 1, kmax < 1, kmax > dim (a Krylov space has at most
  /// dim dimensions) or the basis V (dim × (kmax + 1) numbers) would exceed kMaxBasisEntries;
  /// checked before any allocation, and before kmax + 1 is formed
  Gmres(int dim, int kmax)
      : kmax_(checked(dim, kmax)),
        V_(MatX<double>::Zero(dim, kmax + 1)),
        H_(MatX<double>::Zero(kmax + 1, kmax)),
        g_(VecX<double>::Zero(kmax + 1)),
        cs_(VecX<double>::Zero(kmax)),
        sn_(VecX<double>::Zero(kmax)),
        y_(VecX<double>::Zero(kmax)),
        r_(VecX<double>::Zero(dim)) {}

  int kmax() const { return kmax_; }

  /// @brief Improves x (in: initial guess) towards A x = b with at most kmax iterations.
  /// apply(in, out) writes out = A·in. Returns the number of iterations done; residual_norm()
  /// is then the (estimated) ‖b − A x‖.
  template <typename Op>
  int solve(Op&& apply, const Eigen::Ref<const VecX<double>>& b, Eigen::Ref<VecX<double>> x) {
    // initial residual and first basis vector
    apply(x, r_);
    r_ = b - r_;
    const double beta = r_.norm();
    residual_norm_ = beta;
    if (!(beta > 0) || !std::isfinite(beta)) return 0;
    V_.col(0) = r_ / beta;
    g_.setZero();
    g_[0] = beta;
    int k = 0;
    while (k < kmax_) {
      // Arnoldi step with modified Gram–Schmidt
      auto w = V_.col(k + 1);
      apply(V_.col(k), w);
      for (int j = 0; j <= k; ++j) {
        H_(j, k) = w.dot(V_.col(j));
        w -= H_(j, k) * V_.col(j);
      }
      H_(k + 1, k) = w.norm();
      const bool breakdown = !(H_(k + 1, k) > 1e-14 * beta);
      if (!breakdown) w /= H_(k + 1, k);
      // previous rotations on column k, then a new one to zero H(k+1, k)
      for (int j = 0; j < k; ++j) {
        const double t = cs_[j] * H_(j, k) + sn_[j] * H_(j + 1, k);
        H_(j + 1, k) = -sn_[j] * H_(j, k) + cs_[j] * H_(j + 1, k);
        H_(j, k) = t;
      }
      const double rho = std::hypot(H_(k, k), H_(k + 1, k));
      cs_[k] = rho > 0 ? H_(k, k) / rho : 1.0;
      sn_[k] = rho > 0 ? H_(k + 1, k) / rho : 0.0;
      H_(k, k) = rho;
      H_(k + 1, k) = 0;
      g_[k + 1] = -sn_[k] * g_[k];
      g_[k] = cs_[k] * g_[k];
      ++k;
      if (breakdown) break;
    }
    // least squares: upper-triangular solve, then x += V y
    for (int i = k - 1; i >= 0; --i) {
      double s = g_[i];
      for (int j = i + 1; j < k; ++j) s -= H_(i, j) * y_[j];
      y_[i] = H_(i, i) != 0 ? s / H_(i, i) : 0.0;
    }
    for (int j = 0; j < k; ++j) x += y_[j] * V_.col(j);
    residual_norm_ = std::abs(g_[k]);
    return k;
  }

  double residual_norm() const { return residual_norm_; }

 private:
  static int checked(int dim, int kmax) {
    if (dim < 1) throw std::invalid_argument("GMRES dimension must be at least 1, got " + std::to_string(dim));
    if (kmax < 1) throw std::invalid_argument("kmax must be at least 1, got " + std::to_string(kmax));
    if (kmax > dim) {
      throw std::invalid_argument("kmax must not exceed the GMRES dimension " + std::to_string(dim) +
                                  " (N times the unknowns per stage), got " + std::to_string(kmax));
    }
    const long long entries = static_cast<long long>(dim) * (static_cast<long long>(kmax) + 1);
    if (entries > kMaxBasisEntries) {
      throw std::invalid_argument("GMRES basis of dimension " + std::to_string(dim) + " × (kmax + 1) = " +
                                  std::to_string(entries) + " numbers exceeds " +
                                  std::to_string(kMaxBasisEntries) + " (1 GiB): reduce kmax, got " +
                                  std::to_string(kmax));
    }
    return kmax;
  }

  int kmax_;
  MatX<double> V_, H_;
  VecX<double> g_, cs_, sn_, y_, r_;
  double residual_norm_ = 0;
};

}  // namespace idmpc
