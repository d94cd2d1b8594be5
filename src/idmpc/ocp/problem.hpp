#pragma once
/// @file problem.hpp
/// @brief The two optimal control problems of DESIGN §4 as stage kernels: forward dynamics
/// (input = torque u_i, paper's classic form) and inverse dynamics (input = acceleration a_i,
/// paper eqs. 12, 16, 18, 22–25), each with derivatives by full matrices (the paper's way) or
/// by O(n) adjoint sweeps (DESIGN §5).
///
/// A problem knows one stage at a time: its dynamics, and the derivatives of its discrete
/// Hamiltonian H_i = L(x_i, ·) + λ_{i+1}ᵀ v_i + γ_{i+1}ᵀ a_i. How stages are chained (single or
/// multiple shooting) is the solver layer's business: nothing here loops over the horizon.

#include <string>
#include <vector>

#include "idmpc/model/data.hpp"
#include "idmpc/ocp/cost.hpp"
#include "idmpc/ocp/torque_limits.hpp"
#include "idmpc/spatial/pack.hpp"

namespace idmpc {

enum class Formulation { kForwardDynamics, kInverseDynamics };
enum class DerivativeMode { kMatrix, kAdjoint };

/// @brief "fd"/"id" and "matrix"/"adjoint"; parse throws std::invalid_argument naming the value.
std::string to_string(Formulation f);
std::string to_string(DerivativeMode d);
Formulation parse_formulation(const std::string& s);
DerivativeMode parse_derivative_mode(const std::string& s);

class OcpProblem {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;
  using Out = Eigen::Ref<Vec>;

  /// @param N horizon stages (≥ 1): one dynamics workspace each, kept between the sweeps.
  /// @param limits torque limits (DESIGN §8; default none): each bounded joint adds a dummy
  /// input and a multiplier to every stage.
  /// The torque reference of `cost` is set to u_ref = ID(q_ref, 0, 0), the gravity and spring
  /// torque that holds the target (DESIGN §8). Throws std::invalid_argument on bad sizes,
  /// weights or limits.
  OcpProblem(const Model& model, Formulation formulation, DerivativeMode mode, QuadraticCost cost,
             int N, const TorqueLimits& limits = {});
  OcpProblem(const Model& model, Formulation formulation, DerivativeMode mode, OcpWeights weights,
             Vec q_ref, int N, const TorqueLimits& limits = {})
      : OcpProblem(model, formulation, mode, QuadraticCost(std::move(weights), std::move(q_ref), model.n), N,
                   limits) {}

  int n() const { return model_.n; }
  int N() const { return N_; }
  const Model& model() const { return model_; }
  Formulation formulation() const { return formulation_; }
  DerivativeMode derivative_mode() const { return mode_; }
  const QuadraticCost& cost() const { return cost_; }
  const OcpWeights& weights() const { return cost_.weights(); }
  const TorqueBounds& torque_bounds() const { return bounds_; }
  /// @brief Dummy weight r_d = f × its nominal value (TorqueBounds::set_dummy_weight_factor).
  void set_dummy_weight_factor(double f) { bounds_.set_dummy_weight_factor(f); }
  /// @brief m: bounded joints, each with a dummy input and a multiplier per stage.
  int m() const { return bounds_.m(); }
  /// @brief The estimate d̂ of the joint torque the model misses (DESIGN §10: friction error,
  /// contacts, payload): the model's joint torque is τ = u + d̂ for the actuators' torque u.
  /// FD: a = FD(q, v, u + d̂); ID: u = ID(q, v, a) − d̂. The torque reference becomes
  /// u_ref = ID(q_ref, 0, 0) − d̂ and the torque limits stay on u. Zero until set; size n, finite
  /// (else std::invalid_argument). Held constant over the horizon.
  void set_disturbance(const Vec& d_hat);
  const Vec& disturbance() const { return d_hat_; }
  /// @brief A new target q_ref (size n, finite; else std::invalid_argument): the torque
  /// reference becomes ID(q_ref, 0, 0) − d̂. Allocation-free.
  void set_target(const Vec& q_ref);

  /// @brief Unknowns of one stage: its input (n), dummy inputs d (m), multipliers ρ (m), in
  /// this order; the stage's block F_i of the residual has the same layout.
  int stage_dim() const { return model_.n + 2 * bounds_.m(); }

  /// @brief Stage i's dynamics at (q, v) with its input: FD a = FD(q, v, u + d̂) (ABA); ID
  /// u = ID(q, v, a) − d̂ (RNEA; in matrix mode with ∂ID/∂q, ∂ID/∂v and M from the same pass).
  /// The stage's workspace keeps the linearization for stage_hamiltonian.
  void stage_dynamics(int i, In q, In v, In input, Out output);

  /// @brief ID: the rollout does not depend on the stage dynamics, so kStageLanes stages run at
  /// once in SIMD lanes: with adjoints their RNEA and vector–Jacobian products, in matrix mode
  /// their RNEA derivatives and the products with them. On by default.
  bool lanes_possible() const { return formulation_ == Formulation::kInverseDynamics; }
  void set_stages_in_lanes(bool on) {
    lanes_ = on && lanes_possible();
    costate_lanes_ = on && costate_lanes_possible();
    derivative_lanes_ = on && derivative_lanes_possible();
  }
  bool stages_in_lanes() const { return lanes_; }

  /// @brief FD in matrix mode: the derivatives ∂q̈/∂q, ∂q̈/∂v, M⁻¹ of a stage depend on its state
  /// and torque only, so after the rollout kStageLanes stages run at once
  /// (stage_derivative_lanes); the backward sweep then takes the products with the costates. On
  /// by default, off with set_stages_in_lanes(false).
  bool derivative_lanes_possible() const {
    return formulation_ == Formulation::kForwardDynamics && mode_ == DerivativeMode::kMatrix;
  }
  bool derivative_lanes() const { return derivative_lanes_; }

  /// @brief FD matrix: the derivatives of stages i0 … i0 + count − 1 (count ≤ kStageLanes) at the
  /// columns of q, v and the torques u (n × N), ABA included, into each stage's workspace, where
  /// stage_hamiltonian uses them until release_derivative_lanes().
  void stage_derivative_lanes(int i0, int count, const MatX<double>& q, const MatX<double>& v,
                              const MatX<double>& u);
  /// @brief stage_hamiltonian computes the derivatives again (after stage_derivative_lanes).
  void release_derivative_lanes() { derivatives_from_lanes_ = false; }

  /// @brief FD with adjoints, when the costates are given (multiple shooting's residual at stored
  /// trajectories): then the whole stage — a = FD(q, v, u), μ = M⁻¹γ_{i+1} and the products
  /// (∂ID/∂q)ᵀμ, (∂ID/∂v)ᵀμ — is independent of the other stages, and kStageLanes of them run at
  /// once (stage_lanes_at_costates). On by default, off with set_stages_in_lanes(false).
  bool costate_lanes_possible() const {
    return formulation_ == Formulation::kForwardDynamics && mode_ == DerivativeMode::kAdjoint;
  }
  bool costate_lanes() const { return costate_lanes_; }

  /// @brief Stages i0 … i0 + count − 1 (count ≤ kStageLanes) at given costates: columns of q, v
  /// and the torques u (n × N) in, γ_{i+1} from column i + 1 of gmm (n × (N+1)); the
  /// accelerations a (n × N) out. The products are kept for the stage_hamiltonian calls that
  /// follow, at these same costates, until release_costate_lanes().
  void stage_lanes_at_costates(int i0, int count, const MatX<double>& q, const MatX<double>& v,
                               const MatX<double>& u, const MatX<double>& gmm, MatX<double>& a);
  /// @brief stage_hamiltonian computes its products again (after stage_lanes_at_costates).
  void release_costate_lanes() { costate_products_ = false; }

  /// @brief ID: stages i0 … i0 + count − 1 (count ≤ kStageLanes) at once: columns of q, v, a
  /// (n × N) and of the multipliers rho (m × N) in, u (n × N) out; the products of each stage (by
  /// adjoint sweeps or, in matrix mode, by the derivative matrices) are kept for stage_hamiltonian.
  void stage_dynamics_lanes(int i0, int count, const MatX<double>& q, const MatX<double>& v,
                            const MatX<double>& a, const MatX<double>& rho, MatX<double>& u);

  /// @brief Derivatives of stage i's Hamiltonian
  /// H_i = L(x_i, ·) − r_dᵀd_i + ρ_iᵀ(s∘c(u_i, d_i)) + λ_{i+1}ᵀv_i + γ_{i+1}ᵀa_i (torque_limits.hpp) at its
  /// linearization (after stage_dynamics), with the dummy inputs d and multipliers ρ (size m):
  /// F = (∂H/∂input, ∂H/∂d, ∂H/∂ρ) (size stage_dim), the stage's block F_i of the optimality
  /// residual; with `state` also hq = ∂H/∂q and hv = ∂H/∂v, so that the Euler costates are
  /// λ_i = λ_{i+1} + Δτ hq, γ_i = γ_{i+1} + Δτ hv (DESIGN §4). Without `state` (stage 0), hq
  /// and hv are untouched.
  void stage_hamiltonian(int i, In q, In v, In a, In u, In d, In rho, In lmd_next, In gmm_next,
                         Out hq, Out hv, Out F, bool state);

  /// @brief Terminal costates λ_N = ∂φ/∂q, γ_N = ∂φ/∂v (eqs. 16, 18).
  void terminal_costate(In q, In v, Out lmd, Out gmm) const { cost_.terminal_gradient(q, v, lmd, gmm); }

 private:
  const Model& model_;
  Formulation formulation_;
  DerivativeMode mode_;
  QuadraticCost cost_;
  TorqueBounds bounds_;
  int N_;
  bool lanes_ = false;
  bool costate_lanes_ = false;
  bool derivative_lanes_ = false;
  bool derivatives_from_lanes_ = false;  ///< stage_[i].da_dq, da_dv, Minv hold stage_derivative_lanes' results
  bool costate_products_ = false;  ///< gq_all_, gv_all_, Mw_all_ (= μ) hold stage_lanes_at_costates' products

  Vec d_hat_;                               ///< disturbance estimate (set_disturbance)
  Vec tau_ref_;                             ///< ID(q_ref, 0, 0)
  Vec tau_in_;                              ///< FD: the model's torque u + d̂ of a stage
  Vec u_ref_;                               ///< ID(q_ref, 0, 0) − d̂, handed to the cost
  std::vector<Data> stage_;                 ///< one dynamics workspace per stage
  DataTpl<StagePack> lane_data_;            ///< workspace of the stages in lanes
  VecX<StagePack> ql_, vl_, al_, wl_, rl_;  ///< stage inputs (rl_: multipliers) packed in lanes
  VecX<StagePack> ul_;                      ///< ID: the actuators' torques u = τ − d̂ in lanes
  MatX<double> gq_all_, gv_all_, Mw_all_;   ///< per-stage products from the lanes, n × N
  Vec w_, gq_, gv_, lq_, lv_, la_;          ///< stage scratch
};

}  // namespace idmpc
