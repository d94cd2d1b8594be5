#pragma once
/// @file cost.hpp
/// @brief The quadratic costs of DESIGN §4 (paper eqs. 32–34), by their gradients — all the
/// optimality conditions need:
///   φ(q, v)       = ½(q − q_ref)ᵀQ_q(q − q_ref) + ½vᵀQ_v v          (terminal)
///   L(q, v, a, u) = φ(q, v) + ½aᵀQ_a a + ½(u − u_ref)ᵀR(u − u_ref)   (stage; Q_a only in ID)
/// u_ref is the torque that holds the target (DESIGN §8); zero until set.

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

/// @brief Diagonal weights of the costs, each of size n.
struct OcpWeights {
  VecX<double> Qq, Qv, Qa, R;
};

class QuadraticCost {
 public:
  using In = Eigen::Ref<const VecX<double>>;
  using Out = Eigen::Ref<VecX<double>>;

  /// @brief Costs of an n-joint problem. Throws std::invalid_argument naming a weight or
  /// q_ref of the wrong size, a non-finite entry or a negative weight.
  QuadraticCost(OcpWeights weights, VecX<double> q_ref, int n);

  int n() const { return static_cast<int>(q_ref_.size()); }
  const OcpWeights& weights() const { return w_; }
  const VecX<double>& q_ref() const { return q_ref_; }
  const VecX<double>& u_ref() const { return u_ref_; }
  /// @brief Sets u_ref (size n, finite; else std::invalid_argument), without allocating.
  void set_torque_reference(const In& u_ref);
  /// @brief Sets q_ref (size n, finite; else std::invalid_argument), without allocating; u_ref is
  /// left as it is.
  void set_target(const In& q_ref);

  /// @brief ∂φ/∂q and ∂φ/∂v.
  void terminal_gradient(In q, In v, Out phi_q, Out phi_v) const {
    phi_q = w_.Qq.cwiseProduct(q - q_ref_);
    phi_v = w_.Qv.cwiseProduct(v);
  }
  /// @brief The state part of ∂L/∂q and ∂L/∂v (equal to the terminal gradient's form).
  void state_gradient(In q, In v, Out L_q, Out L_v) const { terminal_gradient(q, v, L_q, L_v); }
  /// @brief ∂L/∂u = R(u − u_ref).
  void torque_gradient(In u, Out L_u) const { L_u = w_.R.cwiseProduct(u - u_ref_); }
  /// @brief ∂L/∂a = Q_a a (inverse-dynamics problem only).
  void acceleration_gradient(In a, Out L_a) const { L_a = w_.Qa.cwiseProduct(a); }

 private:
  OcpWeights w_;
  VecX<double> q_ref_, u_ref_;
};

}  // namespace idmpc
