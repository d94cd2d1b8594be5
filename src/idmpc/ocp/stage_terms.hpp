#pragma once
/// @file stage_terms.hpp
/// @brief What every stage of a problem shares, whatever its formulation: the model, the costs
/// with the references each stage sees, the torque bounds and the disturbance estimate (see
/// formulations.md), and the parts of a stage's Hamiltonian that do not involve the dynamics. The
/// stage models (fd_stages.hpp, id_stages.hpp) add the dynamics' part.
///
/// References: stage i = 0 … N (N: the terminal cost) sees the joint target q_ref,i with
/// v_ref,i, the torque reference u_ref,i = ID(q_ref,i, 0, 0) − d̂ and, with a frame target, the
/// frame's p_ref,i and R_ref,i. Fixed targets are the same at every stage. A moving reference (a
/// Trajectory of the joint target, or of the frame target's position) is sampled at the stage
/// times t_i = t0 + i·Δτ that set_stage_times gives, once per distinct (t0, Δτ): v_ref,i is the
/// joint trajectory's rate there.
///
/// Threads: the const methods read only the object and their arguments. What the frame cost
/// computes along the way is kept in a FrameScratch of the caller's (one per thread), sized on
/// its first use with a frame target, so that a stage evaluation allocates nothing after that.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/model/data.hpp"
#include "idmpc/ocp/cost.hpp"
#include "idmpc/ocp/torque_limits.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "idmpc/spatial/dual.hpp"

namespace idmpc {

class StageTerms {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;
  using Out = Eigen::Ref<Vec>;
  /// The same in dual numbers (exact directional derivatives, formulations.md §Exact products): every stage function
  /// below has an overload for them, with the references constants.
  using DualIn = Eigen::Ref<const VecX<Dual>>;
  using DualOut = Eigen::Ref<VecX<Dual>>;

  /// @brief N stages and the terminal cost; sets the cost's torque reference to
  /// u_ref = ID(q_ref, 0, 0). `mode` says how the frame cost's gradient is formed (matrix: the
  /// Jacobian, then its product; adjoint: the product in one sweep). Throws
  /// std::invalid_argument on a null model, sizes that differ from the model's or bad limits.
  ///
  /// Passive joints (Model::unactuated_joints) have no torque limit (any given there is
  /// dropped). With `passive_constraints` (the ID problem, whose torques are outputs) each
  /// stage has the equality constraint s_E u_E = 0 on their torques u_E, with a multiplier ν
  /// per passive joint after ρ (formulations.md §Under-actuation): H gains s_E νᵀu_E, so
  /// w = ∂H/∂u gains s_E ν on those rows and ∂H/∂ν = s_E u_E. s_E is the mean R of the
  /// actuated joints (1 if that is 0), until set_passive_scale.
  StageTerms(std::shared_ptr<const Model> model, QuadraticCost cost, const TorqueLimits& limits, int N,
             bool frame_jacobian_matrix, bool passive_constraints = false);
  StageTerms(const StageTerms& o);
  StageTerms& operator=(const StageTerms& o);
  StageTerms(StageTerms&&) noexcept = default;
  StageTerms& operator=(StageTerms&&) noexcept = default;
  ~StageTerms() = default;

  /// @brief The frame cost's workspace in scalar S (the frame's kinematics and Jacobian): the
  /// caller's own, passed to state_gradient and close_stage. Empty when made; those calls size
  /// it for the problem's frame target on first use (and again after set_frame_target), and
  /// leave it alone without a frame target.
  template <typename S> struct FrameScratch {
    std::optional<FrameKinematics<S>> kinematics;
    Eigen::Matrix<S, 6, Eigen::Dynamic> jacobian;
    std::uint64_t frame_id = 0;  ///< the frame target it is sized for (StageTerms' frame_id_)
  };

  /// @brief The workspace of stage_cost_at: the references at one time and ID(q_ref, 0, 0).
  struct CostScratch {
    Vec q_ref, v_ref, u_ref, zero;
    Data data;
    Vec3<double> p_ref, rate3;
  };
  /// @brief A CostScratch for this problem's model (allocates).
  CostScratch cost_scratch() const;

  const Model& model() const { return *model_; }
  const std::shared_ptr<const Model>& model_ptr() const { return model_; }
  int n() const { return model_->n; }
  int m() const { return bounds_.m(); }
  /// @brief Equality constraints on the passive joints' torques per stage (0 without
  /// passive_constraints or passive joints); their multipliers ν follow ρ (size m + n_e).
  int n_e() const { return passive_constraints_ ? model_->n - model_->n_actuated() : 0; }
  double passive_scale() const { return passive_scale_; }
  /// @brief s_E (positive and finite, else std::invalid_argument): the same constraint, its rows
  /// scaled (OcpProblem::scale_passive_rows).
  void set_passive_scale(double s);
  const QuadraticCost& cost() const { return cost_; }
  const TorqueBounds& bounds() const { return bounds_; }
  TorqueBounds& bounds() { return bounds_; }
  const Vec& disturbance() const { return d_hat_; }

  /// @brief d̂ (size n, finite; else std::invalid_argument); u_ref = ID(q_ref, 0, 0) − d̂.
  void set_disturbance(const Vec& d_hat);
  /// @brief The fixed joint target q_ref (size n, finite; else std::invalid_argument), at every
  /// stage; u_ref = ID(q_ref, 0, 0) − d̂. Replaces a joint trajectory. Allocation-free.
  void set_target(const Vec& q_ref);

  /// @brief A moving joint target: q_ref(t) (dim n; else std::invalid_argument), with its rate
  /// as v_ref(t); null: back to the fixed target. Sampled at the next set_stage_times.
  void set_joint_trajectory(std::shared_ptr<const Trajectory> q_ref);
  const std::shared_ptr<const Trajectory>& joint_trajectory() const { return joint_trajectory_; }

  /// @brief A frame target (cost.hpp) or none; throws std::invalid_argument naming the frame for a
  /// link outside the model, negative or non-finite weights, a non-finite position or a rotation
  /// that is not orthonormal. Allocates (between runs, not between updates).
  void set_frame_target(std::optional<FrameTarget> target);
  const std::optional<FrameTarget>& frame_target() const { return frame_; }
  /// @brief The frame target's position moving as p_ref(t) (dim 3; else std::invalid_argument);
  /// null: fixed at FrameTarget::position. Needs a frame target.
  void set_frame_trajectory(std::shared_ptr<const Trajectory> p_ref);
  const std::shared_ptr<const Trajectory>& frame_trajectory() const { return frame_trajectory_; }
  /// @brief The fixed frame target's position and rotation, without allocating (needs a frame
  /// target; a position the frame trajectory, if any, overrides).
  void set_frame_pose(const Vec3<double>& position, const Mat3<double>& rotation);

  /// @brief The terminal cost's joint terms as one quadratic ½eᵀP e of e = (q − q_ref,N,
  /// v − v_ref,N) instead of the diagonal Q_q, Q_v (an under-actuated model's LQR value at its
  /// target: horizon_setup.hpp); the frame term, if any, is added as before. P: 2n × 2n, finite,
  /// symmetric (else std::invalid_argument); empty: back to the diagonal. A Gauss–Newton
  /// Hessian of it is not offered: state_hessian throws std::logic_error at the terminal stage.
  void set_terminal_weight(const MatX<double>& P);
  const MatX<double>& terminal_weight() const { return terminal_P_; }

  /// @brief Stage i's references at t_i = t0 + i·Δτ (i = 0 … N) for what moves; allocation-free,
  /// and nothing at all when (t0, Δτ) is the last one given or nothing moves.
  void set_stage_times(double t0, double dtau);
  bool moving() const { return joint_trajectory_ || frame_trajectory_; }

  /// @brief Stage i's joint target, velocity and torque references (i = 0 … N).
  Eigen::Ref<const Vec> q_ref(int i) const { return q_ref_.col(i); }
  Eigen::Ref<const Vec> v_ref(int i) const { return v_ref_.col(i); }
  Eigen::Ref<const Vec> u_ref(int i) const { return u_ref_.col(i); }
  /// @brief Stage i's frame target position (with a frame target).
  Eigen::Ref<const Vec3<double>> frame_position_ref(int i) const { return p_ref_.col(i); }

  /// @brief w = ∂(L + ρᵀ(s∘c) + s_E νᵀu_E)/∂u = R(u − u_ref,i) + 2s∘ρ∘(u − ū) on the bounded
  /// joints of stage i, + s_E ν on the constrained passive ones (u, w size n; ρ size m + n_e,
  /// the torque limits' multipliers then ν).
  void torque_gradient(int i, In u, In rho, Out w) const { torque_gradient_of<double>(i, u, rho, w); }
  void torque_gradient(int i, DualIn u, DualIn rho, DualOut w) const { torque_gradient_of<Dual>(i, u, rho, w); }

  /// @brief torque_gradient of the stages i0 … i0 + count − 1 in SIMD lanes (unused lanes repeat
  /// the last stage): u, w size n, ρ size m, of packs P.
  template <typename P> void torque_gradient(int i0, int count, const VecX<P>& u, const VecX<P>& rho, VecX<P>& w) const {
    const VecX<double>& R = cost_.weights().R;
    constexpr int kLanes = static_cast<int>(sizeof(P) / sizeof(double));
    for (int j = 0; j < n(); ++j) {
      P u_ref;
      for (int k = 0; k < kLanes; ++k) u_ref[k] = u_ref_(j, i0 + std::min(k, count - 1));
      w[j] = R[j] * (u[j] - u_ref);
    }
    for (int k = 0; k < m(); ++k) {
      const int j = bounds_.joints()[static_cast<size_t>(k)];
      w[j] += (2.0 * bounds_.scale()[k]) * rho[k] * (u[j] - bounds_.middle()[k]);
    }
    for (int k = 0; k < n_e(); ++k) w[passive_[static_cast<size_t>(k)]] += passive_scale_ * rho[m() + k];
  }

  /// @brief The state part of stage i's cost gradient, ∂L/∂q and ∂L/∂v (i = N: ∂φ/∂q, ∂φ/∂v,
  /// the terminal costates): the joint terms and, with a frame target, Jᵀf (cost.hpp), computed
  /// in the caller's `frame` workspace.
  void state_gradient(int i, In q, In v, Out L_q, Out L_v, FrameScratch<double>& frame) const;
  void state_gradient(int i, DualIn q, DualIn v, DualOut L_q, DualOut L_v, FrameScratch<Dual>& frame) const;

  /// @brief The Gauss–Newton Hessian of stage i's state cost (i = N: the terminal cost):
  /// H_qq = diag(Q_q) + J_pᵀdiag(w_p)J_p + J_ωᵀ H_θ J_ω and H_vv = Q_v (diagonal), with
  /// H_θ = ½w_o(tr(E)·I − sym E), E = R R_refᵀ, the exact Hessian of w_o(1 − cos θ) in the
  /// rotation's own increment, its negative eigenvalues (far from the target) set to zero. At a
  /// point where every residual vanishes it is the exact Hessian of the cost. Overwrites H_qq
  /// (n × n) and H_vv (n); `frame` as for state_gradient. Allocation-free once `frame` is sized.
  void state_hessian(int i, In q, Eigen::Ref<MatX<double>> H_qq, Out H_vv, FrameScratch<double>& frame) const;

  /// @brief The value of stage i's cost without its acceleration term, the task's stage cost:
  /// ½(q − q_ref,i)ᵀQ_q(·) + ½(v − v_ref,i)ᵀQ_v(·) + ½(u − u_ref,i)ᵀR(·) + φ_frame(q) (cost.hpp).
  /// Allocation-free.
  double stage_cost(int i, In q, In v, In u) const;
  /// @brief The terminal cost φ(x_N): stage N's cost at its torque reference, or with a terminal
  /// weight ½eᵀPe plus the frame term, if any. Allocation-free.
  double terminal_cost(In q, In v) const;
  /// @brief The same cost at the references of time t itself (a moving reference sampled at t,
  /// u_ref = ID(q_ref(t), 0, 0) − d̂), whatever stage times were set last: what a closed loop
  /// accumulates along its measured trajectory. Allocation-free, in the caller's `scratch`
  /// (cost_scratch()).
  double stage_cost_at(double t, In q, In v, In u, CostScratch& scratch) const;

  /// @brief The rest of stage i's block F_i once its first rows hold ∂H/∂input: its last 2m + n_e
  /// rows, ∂H/∂d = −r_d + 2s∘ρ∘d, ∂H/∂ρ = s∘c and ∂H/∂ν = s_E u_E; with `state` also hq = ∂L/∂q + gq and hv = ∂L/∂v + λ_{i+1}
  /// + gv (the Euler step q_{i+1} = q_i + Δτ v_i), for the dynamics' parts gq, gv of ∂H/∂q, ∂H/∂v.
  /// The frame cost's part is computed in the caller's `frame` workspace.
  void close_stage(int i, In q, In v, In u, In d, In rho, In lmd_next, In gq, In gv, Out hq, Out hv, Out F,
                   bool state, FrameScratch<double>& frame) const {
    close_stage_of<double>(i, q, v, u, d, rho, lmd_next, gq, gv, hq, hv, F, state, frame);
  }
  void close_stage(int i, DualIn q, DualIn v, DualIn u, DualIn d, DualIn rho, DualIn lmd_next, DualIn gq,
                   DualIn gv, DualOut hq, DualOut hv, DualOut F, bool state, FrameScratch<Dual>& frame) const {
    close_stage_of<Dual>(i, q, v, u, d, rho, lmd_next, gq, gv, hq, hv, F, state, frame);
  }

 private:
  template <typename S> using RefIn = Eigen::Ref<const VecX<S>>;
  template <typename S> using RefOut = Eigen::Ref<VecX<S>>;

  template <typename S> void torque_gradient_of(int i, RefIn<S> u, RefIn<S> rho, RefOut<S> w) const {
    w = cost_.weights().R.cwiseProduct(u - u_ref_.col(i));
    bounds_.add_torque_gradient(u, rho, w);
    for (int k = 0; k < n_e(); ++k) w[passive_[static_cast<size_t>(k)]] += passive_scale_ * rho[m() + k];
  }
  template <typename S>
  void state_gradient_of(int i, RefIn<S> q, RefIn<S> v, RefOut<S> L_q, RefOut<S> L_v, FrameScratch<S>& frame) const;
  template <typename S>
  void close_stage_of(int i, RefIn<S> q, RefIn<S> v, RefIn<S> u, RefIn<S> d, RefIn<S> rho, RefIn<S> lmd_next,
                      RefIn<S> gq, RefIn<S> gv, RefOut<S> hq, RefOut<S> hv, RefOut<S> F, bool state,
                      FrameScratch<S>& frame) const {
    const int m = this->m(), ne = n_e();
    const Eigen::Index off = F.size() - 2 * m - ne;  // after the input's rows
    if (m > 0) bounds_.dummy_gradients(u, d, rho, F.segment(off, m), F.segment(off + m, m));
    for (int k = 0; k < ne; ++k) F[off + 2 * m + k] = passive_scale_ * u[passive_[static_cast<size_t>(k)]];
    if (!state) return;
    state_gradient(i, q, v, hq, hv, frame);
    hq += gq;
    hv += lmd_next + gv;
  }
  // the cost of (q, v, u) against the given references
  double cost_against(In q, In v, In u, In q_ref, In v_ref, In u_ref, const Vec3<double>& p_ref) const;

  // q_ref_, v_ref_ and u_ref_ = ID(q_ref, 0, 0) − d̂ of every stage, from the fixed target or the
  // joint trajectory's samples
  void update_joint_references();
  // p_ref_ and R_ref_ of every stage from the fixed frame target or the frame trajectory's samples
  void update_frame_references();

  std::shared_ptr<const Model> model_;
  QuadraticCost cost_;
  TorqueBounds bounds_;
  bool passive_constraints_;
  std::vector<int> passive_;  ///< the model's passive joints
  double passive_scale_ = 1;  ///< s_E
  int N_;
  bool frame_jacobian_matrix_;
  Vec d_hat_;      ///< disturbance estimate
  Vec zero_;       ///< v = a = 0 of the torque reference
  MatX<double> q_ref_, v_ref_, u_ref_;  ///< n × (N+1): stage i's references
  Data rnea_data_; ///< workspace of ID(q_ref, 0, 0)
  std::shared_ptr<const Trajectory> joint_trajectory_, frame_trajectory_;
  double t0_ = 0, dtau_ = 0;  ///< stage times of the references' samples
  bool sampled_ = false;      ///< whether the moving references hold samples at (t0_, dtau_)

  MatX<double> terminal_P_;  ///< set_terminal_weight (empty: the diagonal weights)
  std::optional<FrameTarget> frame_;
  std::uint64_t frame_id_ = 0;          ///< the frame target's, unique per set_frame_target (0: none)
  MatX<double> p_ref_;                  ///< 3 × (N+1) frame positions
  Vec3<double> sample3_, rate3_;
};

}  // namespace idmpc
