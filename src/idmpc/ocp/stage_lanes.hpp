#pragma once
/// @file stage_lanes.hpp
/// @brief Stages in SIMD lanes: columns of the horizon's trajectories in and out of packs.

#include <algorithm>

#include "idmpc/spatial/pack.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc::detail {

/// @brief Lane k ← column i0 + min(k, count − 1) + shift of x: unused lanes repeat the last stage.
inline void pack_lanes(const MatX<double>& x, int i0, int count, int shift, VecX<StagePack>& out) {
  for (int k = 0; k < kStageLanes; ++k) {
    const int i = i0 + std::min(k, count - 1) + shift;
    for (Eigen::Index j = 0; j < x.rows(); ++j) out[j][k] = x(j, i);
  }
}

/// @brief The model's torques τ = u + d̂ of the columns of the actuators' torques u, in lanes.
inline void pack_torque_lanes(const MatX<double>& u, const VecX<double>& d_hat, int i0, int count,
                              VecX<StagePack>& out) {
  pack_lanes(u, i0, count, 0, out);
  for (Eigen::Index j = 0; j < u.rows(); ++j) out[j] += d_hat[j];
}

/// @brief Column i0 + k of out ← lane k, for the count stages in use.
inline void unpack_lanes(const VecX<StagePack>& x, int i0, int count, MatX<double>& out) {
  for (int k = 0; k < count; ++k) {
    for (Eigen::Index j = 0; j < x.size(); ++j) out(j, i0 + k) = x[j][k];
  }
}

}  // namespace idmpc::detail
