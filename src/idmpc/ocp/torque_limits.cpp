#include "idmpc/ocp/torque_limits.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace idmpc {
namespace {

std::string joint_text(int j, double lo, double hi) {
  std::ostringstream o;
  o << "torque limit of joint " << j << " is [" << lo << ", " << hi << "]";
  return o.str();
}

}  // namespace

TorqueBounds::TorqueBounds(const TorqueLimits& limits, const VecX<double>& R, int n) {
  const auto lo_size = limits.lower.size(), hi_size = limits.upper.size();
  if (lo_size != 0 || hi_size != 0) {
    if (lo_size != n || hi_size != n) {
      throw std::invalid_argument("torque limits have " + std::to_string(lo_size) + " lower and " +
                                  std::to_string(hi_size) + " upper entries, expected " +
                                  std::to_string(n) + " each (one per joint) or none");
    }
    for (int j = 0; j < n; ++j) {
      const double lo = limits.lower[j], hi = limits.upper[j];
      if (std::isnan(lo) || std::isnan(hi)) throw std::invalid_argument(joint_text(j, lo, hi) + ": NaN");
      if (std::isinf(lo) && lo < 0 && std::isinf(hi) && hi > 0) continue;  // unbounded joint
      if (!std::isfinite(lo) || !std::isfinite(hi)) {
        throw std::invalid_argument(joint_text(j, lo, hi) +
                                    ": expected both bounds finite, or -inf and +inf for an unbounded joint");
      }
      if (!(lo < hi)) throw std::invalid_argument(joint_text(j, lo, hi) + ": expected lower < upper");
      if (!(R[j] > 0)) {
        throw std::invalid_argument(joint_text(j, lo, hi) + ": a bounded joint needs R > 0, got " +
                                    std::to_string(R[j]));
      }
      joint_.push_back(j);
    }
  }
  const int m = static_cast<int>(joint_.size());
  middle_.resize(m);
  half_range_.resize(m);
  scale_.resize(m);
  r_d_nominal_.resize(m);
  for (int k = 0; k < m; ++k) {
    const int j = joint_[static_cast<size_t>(k)];
    middle_[k] = 0.5 * (limits.upper[j] + limits.lower[j]);
    half_range_[k] = 0.5 * (limits.upper[j] - limits.lower[j]);
    scale_[k] = R[j] / (2 * half_range_[k]);
    r_d_nominal_[k] = kDummyWeight * R[j] * half_range_[k];
  }
  r_d_ = r_d_nominal_;
}

void TorqueBounds::cap_scale(const VecX<double>& C) {
  for (int k = 0; k < m(); ++k) {
    const int j = joint_[static_cast<size_t>(k)];
    if (j >= C.size() || !(C[j] > 0) || !std::isfinite(C[j])) {
      throw std::invalid_argument("torque limits: the row cap of joint " + std::to_string(j) +
                                  " must be positive and finite, got " +
                                  (j < C.size() ? std::to_string(C[j]) : std::string("none")));
    }
    scale_[k] = std::min(scale_[k], C[j] / (2 * half_range_[k]));
  }
}

void TorqueBounds::consistent_dummy(In u, Out d, Out rho) const {
  for (int k = 0; k < m(); ++k) {
    const double e = u[joint_[static_cast<size_t>(k)]] - middle_[k], r = half_range_[k];
    d[k] = std::sqrt(std::max(r * r - e * e, kMinimumDummy * kMinimumDummy * r * r));
    rho[k] = r_d_[k] / (2 * scale_[k] * d[k]);
  }
}

double TorqueBounds::violation(const Eigen::Ref<const MatX<double>>& u) const {
  double worst = 0;
  for (int k = 0; k < m(); ++k) {
    const int j = joint_[static_cast<size_t>(k)];
    for (Eigen::Index i = 0; i < u.cols(); ++i) {
      // NaN compares false: a non-finite torque is reported as such, not dropped
      const double excess = std::abs(u(j, i) - middle_[k]) - half_range_[k];
      if (!(excess <= worst)) worst = excess;
    }
  }
  return worst;
}

}  // namespace idmpc
