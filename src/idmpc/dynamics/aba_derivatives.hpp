#pragma once
/// @file aba_derivatives.hpp
/// @brief Forward-dynamics derivatives as −M⁻¹·(RNEA derivatives) at the ABA result
/// (Carpentier & Mansard 2018): ∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ = M⁻¹.
///
/// Every column of M⁻¹, ∂q̈/∂q and ∂q̈/∂v is a solve through the ABA factorization (O(n) each,
/// O(n²) in all), never a dense inverse or an explicit M⁻¹·∂τ/∂q product: on long chains M is
/// ill-conditioned (cond ≈ 1e6 at n = 32) and those put rounding noise into F that the 1e-8
/// forward differences of C/GMRES amplify into useless Jacobian products (14 % error at n = 32).

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/rnea_derivatives.hpp"

namespace idmpc {

/// @brief Fills data.qdd = FD(q, v, τ), data.da_dq, data.da_dv and data.Minv (= ∂q̈/∂τ).
template <typename S, typename Q, typename Vv, typename T>
void aba_derivatives(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                     const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<T>& tau) {
  aba(model, data, q, v, tau);
  rnea_derivatives(model, data, q, v, data.qdd);  // same q: X_up unchanged for minv_apply
  // every column through the ABA factorization: O(n²) and free of the cancellation that an
  // explicit −M⁻¹·∂τ/∂q product suffers when M is ill-conditioned
  data.Minv.setIdentity();
  for (int j = 0; j < model.n; ++j) {
    data.Minv.col(j) = minv_apply(model, data, data.Minv.col(j));
    data.da_dq.col(j) = -minv_apply(model, data, data.dtau_dq.col(j));
    data.da_dv.col(j) = -minv_apply(model, data, data.dtau_dv.col(j));
  }
}

}  // namespace idmpc
