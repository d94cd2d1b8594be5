#pragma once
/// @file horizon.hpp
/// @brief Growing horizon T(t) = T_f (1 − e^{−αt}) (paper eq. 31).

#include <cmath>
#include <stdexcept>
#include <string>

namespace idmpc {

struct Horizon {
  double Tf = 0.5;
  double alpha = 1.0;

  Horizon(double Tf_, double alpha_) : Tf(Tf_), alpha(alpha_) {
    if (!(Tf > 0) || !std::isfinite(Tf)) {
      throw std::invalid_argument("horizon length Tf must be positive, got " + std::to_string(Tf));
    }
    if (!(alpha >= 0) || !std::isfinite(alpha)) {
      throw std::invalid_argument("horizon growth alpha must be non-negative, got " + std::to_string(alpha));
    }
  }
  /// @brief T(t); with α = 0 the horizon is fixed at T_f.
  double length(double t) const { return alpha > 0 ? Tf * (1.0 - std::exp(-alpha * t)) : Tf; }
};

}  // namespace idmpc
