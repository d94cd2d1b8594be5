#pragma once
/// @file problem.hpp
/// @brief The two optimal control problems of formulations.md behind one stage interface: forward
/// dynamics (input = torque u_i, the paper's classic form; FdStages) and inverse dynamics (input =
/// acceleration a_i, paper eqs. 12, 16, 18, 22–25; IdStages), each with derivatives by full
/// matrices (the paper's way) or by O(n) adjoint sweeps (formulations.md §Derivatives), with or without stages in
/// SIMD lanes. The combination is a type, chosen at construction (and by set_stages_in_lanes).
///
/// A problem knows one stage at a time: its dynamics, and the derivatives of its discrete
/// Hamiltonian H_i = L(x_i, ·) + λ_{i+1}ᵀ v_i + γ_{i+1}ᵀ a_i. How stages are chained (single or
/// multiple shooting) is the solver layer's business: nothing here loops over the horizon but
/// what runs across stages in lanes. One evaluation of the horizon is one Evaluation token
/// (begin_evaluation): what the stages keep between its calls is read only under that token.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "idmpc/model/data.hpp"
#include "idmpc/ocp/cost.hpp"
#include "idmpc/ocp/local_model.hpp"
#include "idmpc/ocp/stage_model.hpp"
#include "idmpc/ocp/stage_terms.hpp"
#include "idmpc/ocp/torque_limits.hpp"

namespace idmpc {

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

  /// @param model shared, never modified; the problem keeps it alive.
  /// @param N horizon stages (≥ 1): one workspace each, sized by the formulation and mode, kept
  /// between the sweeps.
  /// @param limits torque limits (formulations.md §Torque limits; default none): each bounded joint adds a dummy
  /// input and a multiplier to every stage.
  /// The torque reference of `cost` is set to u_ref = ID(q_ref, 0, 0), the gravity and spring
  /// torque that holds the target (formulations.md §Torque reference). Stages run in SIMD lanes where they can (see
  /// set_stages_in_lanes). Throws std::invalid_argument on a null model, bad sizes, weights or
  /// limits.
  OcpProblem(std::shared_ptr<const Model> model, Formulation formulation, DerivativeMode mode, QuadraticCost cost,
             int N, const TorqueLimits& limits = {});
  OcpProblem(std::shared_ptr<const Model> model, Formulation formulation, DerivativeMode mode, OcpWeights weights,
             Vec q_ref, int N, const TorqueLimits& limits = {})
      : OcpProblem(model, formulation, mode, QuadraticCost(std::move(weights), std::move(q_ref), checked_n(model)),
                   N, limits) {}
  /// @brief As above, with a copy of `model`.
  OcpProblem(const Model& model, Formulation formulation, DerivativeMode mode, QuadraticCost cost, int N,
             const TorqueLimits& limits = {})
      : OcpProblem(std::make_shared<const Model>(model), formulation, mode, std::move(cost), N, limits) {}
  OcpProblem(const Model& model, Formulation formulation, DerivativeMode mode, OcpWeights weights, Vec q_ref, int N,
             const TorqueLimits& limits = {})
      : OcpProblem(std::make_shared<const Model>(model), formulation, mode, std::move(weights), std::move(q_ref), N,
                   limits) {}

  OcpProblem(const OcpProblem& o);
  OcpProblem& operator=(const OcpProblem& o);
  OcpProblem(OcpProblem&&) noexcept = default;
  OcpProblem& operator=(OcpProblem&&) noexcept = default;
  ~OcpProblem() = default;

  int n() const { return terms_.n(); }
  int N() const { return N_; }
  const Model& model() const { return terms_.model(); }
  const std::shared_ptr<const Model>& model_ptr() const { return terms_.model_ptr(); }
  Formulation formulation() const { return formulation_; }
  DerivativeMode derivative_mode() const { return mode_; }
  const QuadraticCost& cost() const { return terms_.cost(); }
  const OcpWeights& weights() const { return terms_.cost().weights(); }
  const TorqueBounds& torque_bounds() const { return terms_.bounds(); }
  /// @brief Dummy weight r_d = f × its nominal value (TorqueBounds::set_dummy_weight_factor).
  void set_dummy_weight_factor(double f) { terms_.bounds().set_dummy_weight_factor(f); }
  /// @brief The diagonal of the input's block of ∂F/∂U at the first stage, estimated at q_ref for a
  /// horizon T_f (size n; FD: the actuated joints' entries): the stage's own torque cost in the input
  /// plus the horizon's joint weights reached through it, with
  /// c_k = Δτ·(Q_q,k T_f³/3 + Q_v,k T_f), the cost's curvature in a velocity step of joint k at
  /// the start (Δτ = T_f/N): ID (input a)  C_j = (MᵀRM)_jj + Q_a,j + c_j;
  /// FD (input u)  C_j = R_j + Σ_k (M⁻¹)_kj² c_k ≥ R_j.
  VecX<double> input_block_diagonal(double Tf) const;
  /// @brief Caps the torque limits' row scale at the input's block (TorqueBounds::cap_scale with
  /// input_block_diagonal(T_f)): the same constraint, rows no larger than the input's. Binds only
  /// in ID, on joints whose R exceeds (MᵀRM)_jj + Q_a + c_j (light joints); FD's C_j ≥ R_j.
  void cap_limit_rows(double Tf);
  /// @brief ID on an under-actuated model: the passive torques' equality rows (s_E, stage_terms.hpp)
  /// at the input's block, s_E = mean over the passive joints E of C_E / M_EE with C =
  /// input_block_diagonal(T_f) and M at q_ref: the row's entry s_E·M_EE on the joint's own
  /// acceleration is then the block's diagonal there. The same constraint and optimum; only the
  /// conditioning GMRES sees changes. Nothing without passive-torque constraints (FD, fully actuated).
  void scale_passive_rows(double Tf);
  /// @brief m: bounded joints, each with a dummy input and a multiplier per stage.
  int m() const { return terms_.m(); }
  /// @brief The estimate d̂ of the joint torque the model misses (formulations.md §Disturbance observer: friction error,
  /// contacts, payload): the model's joint torque is τ = u + d̂ for the actuators' torque u.
  /// FD: a = FD(q, v, u + d̂); ID: u = ID(q, v, a) − d̂. The torque reference becomes
  /// u_ref = ID(q_ref, 0, 0) − d̂ and the torque limits stay on u. Zero until set; size n, finite
  /// (else std::invalid_argument). Held constant over the horizon.
  void set_disturbance(const Vec& d_hat) { terms_.set_disturbance(d_hat); }
  const Vec& disturbance() const { return terms_.disturbance(); }
  /// @brief The target q_ref of the costs (size n, finite; else std::invalid_argument), with the
  /// torque reference u_ref = ID(q_ref, 0, 0) − d̂ recomputed. Allocation-free; between updates.
  void set_target(const Vec& q_ref) { terms_.set_target(q_ref); }
  /// @brief A moving joint target q_ref(t) with v_ref(t) its rate (StageTerms); null: the fixed one.
  void set_joint_trajectory(std::shared_ptr<const Trajectory> q_ref) { terms_.set_joint_trajectory(std::move(q_ref)); }
  /// @brief A frame target (cost.hpp) or none, and its position moving as p_ref(t) (null: fixed).
  void set_frame_target(std::optional<FrameTarget> target) { terms_.set_frame_target(std::move(target)); }
  void set_frame_trajectory(std::shared_ptr<const Trajectory> p_ref) { terms_.set_frame_trajectory(std::move(p_ref)); }
  /// @brief The fixed frame target's pose (needs a frame target), without allocating: between updates.
  void set_frame_pose(const Vec3<double>& position, const Mat3<double>& rotation) {
    terms_.set_frame_pose(position, rotation);
  }
  /// @brief The terminal cost's joint terms as ½eᵀP e (StageTerms::set_terminal_weight).
  void set_terminal_weight(const MatX<double>& P) { terms_.set_terminal_weight(P); }
  /// @brief The references every stage sees (StageTerms): q_ref(i), v_ref(i), u_ref(i), frame.
  const StageTerms& terms() const { return terms_; }
  /// @brief Stage i's references at t0 + i·Δτ (what moves; nothing when nothing does).
  void set_stage_times(double t0, double dtau) { terms_.set_stage_times(t0, dtau); }

  /// @brief The stage's input: FD the actuators' torques (n_u = Model::n_actuated(), the
  /// passive joints' torque zero), ID the accelerations (n).
  int input_dim() const {
    return formulation_ == Formulation::kForwardDynamics ? model().n_actuated() : n();
  }
  /// @brief ID's equality constraints on the passive joints' torques per stage (n − n_u; FD: 0).
  int equality_dim() const { return terms_.n_e(); }
  /// @brief Unknowns of one stage: its input (input_dim), dummy inputs d (m), multipliers ρ (m)
  /// of the torque limits, multipliers ν (equality_dim) of the passive torques, in this order;
  /// the stage's block F_i of the residual has the same layout.
  int stage_dim() const { return input_dim() + 2 * m() + equality_dim(); }
  /// @brief Where d starts in a stage's block (= input_dim).
  int dummy_offset() const { return input_dim(); }
  /// @brief The joints a FD input's entries drive, increasing (Model::actuated_joints).
  const std::vector<int>& input_joints() const { return model().actuated_joints; }

  /// @brief Stages in SIMD lanes wherever they are independent (on by default): ID's dynamics and
  /// products after the rollout (stages_in_lanes); FD matrix's stage derivatives after the rollout
  /// (derivative_lanes); FD adjoint's whole stages at given costates (costate_lanes, multiple
  /// shooting). Switching rebuilds the stages' workspaces.
  void set_stages_in_lanes(bool on);
  bool lanes_possible() const { return formulation_ == Formulation::kInverseDynamics; }
  bool stages_in_lanes() const { return lanes_ && lanes_possible(); }
  bool derivative_lanes_possible() const {
    return formulation_ == Formulation::kForwardDynamics && mode_ == DerivativeMode::kMatrix;
  }
  bool derivative_lanes() const { return lanes_ && derivative_lanes_possible(); }
  bool costate_lanes_possible() const {
    return formulation_ == Formulation::kForwardDynamics && mode_ == DerivativeMode::kAdjoint;
  }
  bool costate_lanes() const { return lanes_ && costate_lanes_possible(); }

  /// @brief A new evaluation of the horizon: the token of all stage calls that follow, until
  /// the next one.
  Evaluation begin_evaluation() { return Evaluation{++evaluations_}; }

  /// @brief Stage i's dynamics at (q, v) with its input: FD a = FD(q, v, u + d̂) (ABA); ID
  /// u = ID(q, v, a) − d̂ (RNEA; in matrix mode with ∂ID/∂q, ∂ID/∂v and M from the same pass).
  /// The stage keeps its linearization for stage_hamiltonian under `ev` (ID with lanes: not;
  /// there stages_at_states does).
  void stage_dynamics(Evaluation ev, int i, In q, In v, In input, Out output) {
    stages_->dynamics(terms_, ev, i, q, v, input, output);
  }
  /// @brief After a rollout, with the states of stages 0 … x.stages − 1 known (FD: after each
  /// stage's stage_dynamics): ID's dynamics of every stage (x.u out) with their products; FD
  /// matrix's derivatives in lanes.
  void stages_at_states(Evaluation ev, StageTrajectories& x) { stages_->at_states(terms_, ev, x); }
  /// @brief Every stage at given states and costates x.gmm (multiple shooting): the dynamics (FD:
  /// x.a out; ID: x.u out) and, FD adjoint in lanes, the whole stage.
  void stages_at_costates(Evaluation ev, StageTrajectories& x) { stages_->at_costates(terms_, ev, x); }

  /// @brief Derivatives of stage i's Hamiltonian
  /// H_i = L(x_i, ·) − r_dᵀd_i + ρ_iᵀ(s∘c(u_i, d_i)) + s_E ν_iᵀu_E,i + λ_{i+1}ᵀv_i + γ_{i+1}ᵀa_i
  /// (torque_limits.hpp, stage_terms.hpp) at its linearization of evaluation `ev`, with the
  /// dummy inputs d (size m) and multipliers (ρ, ν) (size m + equality_dim); `u` the joint
  /// torques (size n, FD: zero on the passive joints):
  /// F = (∂H/∂input, ∂H/∂d, ∂H/∂ρ) (size stage_dim), the stage's block F_i of the optimality
  /// residual; with `state` also hq = ∂H/∂q and hv = ∂H/∂v, so that the Euler costates are
  /// λ_i = λ_{i+1} + Δτ hq, γ_i = γ_{i+1} + Δτ hv (formulations.md §Rollout, costates and residual). Without `state` (stage 0), hq
  /// and hv are untouched. Throws std::logic_error if the stage has no linearization of `ev`.
  void stage_hamiltonian(Evaluation ev, int i, In q, In v, In a, In u, In d, In rho, In lmd_next, In gmm_next,
                         Out hq, Out hv, Out F, bool state) {
    stages_->hamiltonian(terms_, ev, i, q, v, a, u, d, rho, lmd_next, gmm_next, hq, hv, F, state);
  }

  /// @brief StageTerms::stage_cost of stage i at its references of the last evaluation.
  double stage_cost(int i, In q, In v, In u) const { return terms_.stage_cost(i, q, v, u); }

  /// @brief Terminal costates λ_N = ∂φ/∂q, γ_N = ∂φ/∂v (eqs. 16, 18) at the end of a horizon of
  /// `stages` stages (its references are those of stage `stages`).
  void terminal_costate(int stages, In q, In v, Out lmd, Out gmm) {
    terms_.state_gradient(stages, q, v, lmd, gmm, terminal_frame_);
  }

  /// @brief The stage calls above in dual numbers (StageModel): the same arithmetic, stage by
  /// stage, with the tangents carried along (exact directional products, formulations.md §Exact products). Need
  /// reserve_dual first.
  using DualIn = StageModel::DualIn;
  using DualOut = StageModel::DualOut;
  void stage_dynamics(Evaluation ev, int i, DualIn q, DualIn v, DualIn input, DualOut output) {
    stages_->dynamics(terms_, ev, i, q, v, input, output);
  }
  void stage_hamiltonian(Evaluation ev, int i, DualIn q, DualIn v, DualIn a, DualIn u, DualIn d, DualIn rho,
                         DualIn lmd_next, DualIn gmm_next, DualOut hq, DualOut hv, DualOut F, bool state) {
    stages_->hamiltonian(terms_, ev, i, q, v, a, u, d, rho, lmd_next, gmm_next, hq, hv, F, state);
  }
  void terminal_costate(int stages, DualIn q, DualIn v, DualOut lmd, DualOut gmm) {
    terms_.state_gradient(stages, q, v, lmd, gmm, terminal_frame_dual_);
  }
  /// @brief Sizes the stages' dual-number workspaces (kept across set_stages_in_lanes).
  void reserve_dual() {
    dual_ = true;
    stages_->reserve_dual(terms_.model());
  }
  bool dual_reserved() const { return dual_; }

  /// @brief A workspace of this formulation's stage local model (local_model.hpp): what a
  /// Riccati-type solver reads. The formulation picks the type here and nowhere else.
  std::unique_ptr<LocalModel> make_local_model() const;

  /// @brief Bytes of heap the stages' workspaces own (per-stage workspaces, lanes and the
  /// products kept from them).
  std::size_t workspace_bytes() const { return stages_->workspace_bytes(); }

 private:
  static int checked_n(const std::shared_ptr<const Model>& model);
  // the stage model of this formulation, mode and lanes
  std::unique_ptr<StageModel> make_stages() const;

  StageTerms terms_;
  StageTerms::FrameScratch<double> terminal_frame_;  ///< the terminal cost's frame kinematics
  StageTerms::FrameScratch<Dual> terminal_frame_dual_;
  Formulation formulation_;
  DerivativeMode mode_;
  int N_;
  bool lanes_ = true;
  bool dual_ = false;
  std::unique_ptr<StageModel> stages_;
  std::uint64_t evaluations_ = 0;
};

}  // namespace idmpc
