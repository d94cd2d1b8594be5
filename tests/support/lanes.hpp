#pragma once
/// @file lanes.hpp
/// @brief SIMD-pack lanes in the tests that compare a kernel's pack instantiation with its double
/// one: a pack vector from one double vector per lane, and one lane of any pack matrix back as
/// doubles.

#include <vector>

#include "idmpc/spatial/pack.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc::test {

/// @brief The vector whose lane k is per_lane[k] (W vectors of equal size; lanes past their
/// number are zero).
template <typename P = StagePack, typename V>
Eigen::Matrix<P, V::RowsAtCompileTime, 1> packed(const std::vector<V>& per_lane) {
  const Eigen::Index rows = per_lane.empty() ? 0 : per_lane.front().size();
  Eigen::Matrix<P, V::RowsAtCompileTime, 1> out(rows);
  for (Eigen::Index i = 0; i < rows; ++i) {
    out[i] = P(0.0);
    for (size_t k = 0; k < per_lane.size(); ++k) out[i][static_cast<int>(k)] = per_lane[k][i];
  }
  return out;
}

/// @brief Lane k of a matrix (or vector) of packs, as doubles.
template <typename X> MatX<double> lane(const Eigen::DenseBase<X>& x, int k) {
  MatX<double> out(x.rows(), x.cols());
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    for (Eigen::Index c = 0; c < x.cols(); ++c) out(r, c) = x.derived().coeff(r, c)[k];
  }
  return out;
}

}  // namespace idmpc::test
