#pragma once
/// @file cost.hpp
/// @brief The costs of formulations.md §Costs (paper eqs. 32–34), by their gradients — all the optimality
/// conditions need:
///   φ(q, v)       = ½(q − q_ref)ᵀQ_q(q − q_ref) + ½(v − v_ref)ᵀQ_v(v − v_ref) + φ_frame(q)  (terminal)
///   L(q, v, a, u) = φ(q, v) + ½aᵀQ_a a + ½(u − u_ref)ᵀR(u − u_ref)   (stage; Q_a only in ID)
/// u_ref is the torque that holds the target (formulations.md §Torque reference). v_ref is zero but for a
/// moving joint reference (its rate); φ_frame is the cost of an optional frame target
/// (FrameTarget). QuadraticCost holds the weights and the fixed joint target; the references
/// each stage sees, moving or not, are StageTerms' (stage_terms.hpp).

#include "idmpc/model/frame.hpp"
#include "idmpc/spatial/dual.hpp"
#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

/// @brief Diagonal weights of the costs, each of size n.
struct OcpWeights {
  VecX<double> Qq, Qv, Qa, R;
};

/// @brief A target for a frame of the robot (a MuJoCo site or body: the tool point, the flange),
/// with its stage and terminal cost
///   φ_frame(q) = ½(p − p_ref)ᵀ diag(w_p) (p − p_ref) + w_o (1 − cos θ),
/// p the frame's world position and θ the angle of R_refᵀR, the rotation from the target's
/// orientation to the frame's: w_o(1 − cos θ) = ¼w_o‖R − R_ref‖²_F (the chordal metric, smooth
/// everywhere), ≈ ½w_o θ² near the target. Its gradient is Jᵀf for the frame's Jacobian J
/// (kinematics.hpp): f_lin = w_p∘(p − p_ref), f_ang = ½w_o vee(R R_refᵀ − R_ref Rᵀ).
struct FrameTarget {
  Frame frame;
  Vec3<double> position_weight = Vec3<double>::Zero();  ///< w_p [1/m²], per world axis
  double orientation_weight = 0;                         ///< w_o
  Vec3<double> position = Vec3<double>::Zero();          ///< p_ref, world coordinates
  Mat3<double> rotation = Mat3<double>::Identity();      ///< R_ref: target axes in world coordinates
};

/// @brief The angle θ ∈ [0, π] of R_refᵀR (the orientation error the frame cost weighs).
double rotation_angle(const Mat3<double>& R, const Mat3<double>& R_ref);

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
  /// @brief Sets q_ref (size n, finite; else std::invalid_argument), without allocating.
  void set_target(const In& q_ref);

  /// @brief ∂L/∂a = Q_a a (inverse-dynamics problem only).
  void acceleration_gradient(In a, Out L_a) const { L_a = w_.Qa.cwiseProduct(a); }
  void acceleration_gradient(const Eigen::Ref<const VecX<Dual>>& a, Eigen::Ref<VecX<Dual>> L_a) const {
    L_a = w_.Qa.cwiseProduct(a);
  }

 private:
  OcpWeights w_;
  VecX<double> q_ref_;
};

}  // namespace idmpc
