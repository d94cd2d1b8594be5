#pragma once
/// @file finite_difference.hpp
/// @brief The one central-difference helper: every analytic derivative has a twin built here.

#include <cmath>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

/// @brief Step for central differences: ε^(1/3) scaled by the magnitude of x_j, which
/// balances truncation O(h²) against rounding O(ε/h).
inline double central_difference_step(double xj) {
  return 6.0554544523933395e-06 * std::max(1.0, std::abs(xj));  // cbrt(2.22e-16)
}

/// @brief Jacobian of f: ℝⁿ → ℝᵐ at x by central differences, J(:, j) = (f(x+h e_j) −
/// f(x−h e_j)) / 2h. f takes a VecX<double> and returns something convertible to VecX<double>.
template <typename Fn> MatX<double> central_difference_jacobian(Fn&& f, const VecX<double>& x) {
  VecX<double> xp = x;
  const VecX<double> f0 = f(x);
  MatX<double> J(f0.size(), x.size());
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    const double h = central_difference_step(x[j]);
    xp[j] = x[j] + h;
    const VecX<double> fp = f(xp);
    xp[j] = x[j] - h;
    const VecX<double> fm = f(xp);
    xp[j] = x[j];
    J.col(j) = (fp - fm) / (2 * h);
  }
  return J;
}

}  // namespace idmpc
