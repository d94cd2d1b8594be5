#pragma once
/// @file aba_derivatives.hpp
/// @brief Forward-dynamics derivatives as −M⁻¹·(RNEA derivatives) at the ABA result
/// (Carpentier & Mansard 2018): ∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ = M⁻¹.
///
/// As in Pinocchio's computeABADerivatives (what the paper ran): M⁻¹ from the ABA
/// factorization (the sweeps of all n unit loads in the world frame, O(n²)), then
/// ∂q̈/∂q = −M⁻¹·∂τ/∂q and ∂q̈/∂v = −M⁻¹·∂τ/∂v as dense products. A dense Cholesky of M would be numerically much worse
/// on ill-conditioned chains; the explicit products still carry rounding that C/GMRES's 1e-8
/// forward differences amplify (Fréchet-product error 14 % at n = 32 in the FD problem, against
/// 2 % when every column is solved through the factorization at twice the cost, and 6e-5 for
/// the adjoint mode): see the README.

#include <type_traits>

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/minv.hpp"
#include "idmpc/dynamics/rnea_derivatives.hpp"

namespace idmpc {

namespace detail {

/// @brief C = −A·B: Eigen's product for double; for SIMD packs, whose lanes Eigen's product
/// kernels cannot take (they compare scalars), column by column.
template <typename S> void negated_product(const MatX<S>& A, const MatX<S>& B, MatX<S>& C) {
  if constexpr (std::is_floating_point_v<S>) {
    C.noalias() = -A * B;
  } else {
    for (Eigen::Index j = 0; j < B.cols(); ++j) {
      C.col(j).setZero();
      for (Eigen::Index k = 0; k < A.cols(); ++k) {
        const S b = B(k, j);
        for (Eigen::Index i = 0; i < A.rows(); ++i) C(i, j) -= A(i, k) * b;
      }
    }
  }
}

}  // namespace detail

/// @brief ∂q̈/∂q, ∂q̈/∂v and M⁻¹ into data.da_dq, da_dv, Minv. Precondition: data holds
/// aba(model, data, q, v, τ) at this point (its q̈ and articulated inertias are reused); checked
/// in debug builds.
template <typename S, typename Q, typename Vv>
void aba_derivatives_after_aba(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                               const Eigen::MatrixBase<Vv>& v) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && q.size() == model.n && v.size() == model.n,
                    "aba_derivatives_after_aba: q, v must have size model.n");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::rnea_derivatives() | DataParts::minv_matrix() |
                                    DataParts::aba_derivatives()),
                    "aba_derivatives_after_aba: data was made without its derivative parts");
  IDMPC_DEBUG_CHECK(data.passes.holds_aba_at(q, v),
                    "aba_derivatives_after_aba needs aba(model, data, q, v, tau) at this (q, v) "
                    "first, and no other algorithm at another q since");
  // same q: aba's joint transforms X_up are reused, no sin/cos again
  detail::rnea_derivatives_impl<false>(model, data, q, v, data.qdd);
  // M⁻¹ by the ABA sweeps of the unit loads, in the world frame of the derivatives, then the
  // dense products
  for (int i = 0; i < model.n; ++i) data.oUD[i] = data.oX[i].apply_transpose_force(data.Ud[i]);
  detail::minv_world_sweeps(model, data, data.Dinv);
  detail::negated_product(data.Minv, data.dtau_dq, data.da_dq);
  detail::negated_product(data.Minv, data.dtau_dv, data.da_dv);
}

/// @brief Fills data.qdd = FD(q, v, τ), data.da_dq, data.da_dv and data.Minv (= ∂q̈/∂τ).
template <typename S, typename Q, typename Vv, typename T>
void aba_derivatives(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Q>& q,
                     const Eigen::MatrixBase<Vv>& v, const Eigen::MatrixBase<T>& tau) {
  aba(model, data, q, v, tau);
  aba_derivatives_after_aba(model, data, q, v);
}

}  // namespace idmpc
