#pragma once
/// @file aba_derivatives.hpp
/// @brief Forward-dynamics derivatives as −M⁻¹·(RNEA derivatives) at the ABA result
/// (Carpentier & Mansard 2018): ∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ = M⁻¹.

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/rnea_derivatives.hpp"

namespace idmpc {

/// @brief Fills data.qdd = FD(q, v, τ), data.da_dq, data.da_dv and data.Minv (= ∂q̈/∂τ).
template <typename S, typename Q, typename Vv, typename T>
void aba_derivatives(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                     const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<T>& tau) {
  aba(model, data, q, v, tau);
  rnea_derivatives(model, data, q, v, data.qdd);
  // M⁻¹ by Cholesky of the CRBA matrix the derivatives produced
  data.llt.compute(data.M);
  data.Minv.setIdentity();
  data.llt.solveInPlace(data.Minv);
  data.da_dq.noalias() = -data.Minv * data.dtau_dq;
  data.da_dv.noalias() = -data.Minv * data.dtau_dv;
}

}  // namespace idmpc
