#pragma once
/// @file riccati.hpp
/// @brief Multiple-shooting Gauss–Newton SQP with a Riccati recursion (docs/solvers.md), one
/// solver for every formulation: it reads the stages' local models (ocp/local_model.hpp) and
/// nothing else of them.
///
/// Unknowns: the states x_1 … x_N, the inputs u_0 … u_{N−1} (FD torques or ID accelerations),
/// with x_0 the measured state; horizon T_f fixed, Δτ = T_f/N. An iteration linearizes every stage
/// at the current trajectory (the defects b_i = f(x_i, u_i) − x_{i+1} stay in the QP), solves the
/// QP by the backward Riccati recursion and its forward sweep, and steps.
///
/// Torque limits (both formulations: FD bounds the input, ID the nonlinear τ(x, a) = ID − d̂) by a
/// primal-dual interior point: per bounded joint and side a slack s > 0 and a multiplier z > 0,
/// g(x, u) + s = 0, s∘z = μ, with μ_j = κ·Δτ·R_j·(Δ_j/2)² (κ = RiccatiSettings::barrier: the
/// barrier's pull relative to the torque cost), the barrier recentred at the torque reference
/// u_ref (its slope there subtracted) so that it moves no target held within the limits. Slacks
/// and multipliers are eliminated stage by
/// stage, so a limit costs one more weight on τ in the stage's Hessian, W = ΔτR + z/s, and
/// the Riccati recursion is unchanged; steps keep s, z > 0 (fraction to the boundary).
///
/// Under-actuation. FD's input is the n_u actuators' torques (τ = Sᵀu), and nothing else changes.
/// ID keeps the n accelerations as its input, with the passive joints' torques τ_E(x, a) = 0 as
/// each stage's equality constraint. The solver eliminates it stage by stage in the QP: with
/// M_EE, M_EU the passive rows of τ_u = M, the linearized constraint
/// c + C_x dx + M_EU da_U + M_EE da_E = 0 gives da_E from (dx, da_U), so
///   da = Z dw + Y_x dx + y_0,  Z = [I; −M_EE⁻¹M_EU],  Y_x = [0; −M_EE⁻¹C_x],  y_0 = [0; −M_EE⁻¹c],
/// with the actuated accelerations w = a_U (n_u) as the recursion's input: the stage's A, B,
/// cost and defect are rewritten in (dx, dw) and the recursion runs unchanged on them (the
/// null-space method of constrained Riccati recursions, with the null space of the actuated
/// coordinates). The step satisfies the linearized constraint; the residual c left by its
/// curvature is in the KKT residual and, weighted by its multiplier ν = −M_EE⁻¹(ℓ_u + Bᵀλ)_E,
/// in the merit, like a defect.
///
/// Real-time iteration (RiccatiSettings::iterations = 1, the default): the previous solution
/// shifted by Δt along the stages is the start of one full step per update. Converged mode
/// (iterations > 1, tolerance > 0): iterations with a backtracking line search on the ℓ1 merit
/// (cost + barrier + ν‖defects, g + s‖₁) until the KKT residual falls below the tolerance.
/// initialize converges from a hold-the-state guess. Regularization: Q_uu + εI with ε raised
/// tenfold while a stage's Q_uu is not positive definite.

#include <functional>
#include <string>
#include <vector>

#include "idmpc/model/data.hpp"
#include "idmpc/ocp/local_model.hpp"
#include "idmpc/solver/mpc_solver.hpp"

namespace idmpc {

struct RiccatiSettings {
  int iterations = 1;            ///< SQP iterations per update (1: real-time iteration)
  double tolerance = 0;          ///< … fewer when the KKT residual falls below this (0: all)
  int init_iterations = 100;     ///< SQP iterations of the start, at most
  double init_tolerance = 1e-8;  ///< the start's KKT residual
  double barrier = 1e-3;         ///< κ of the torque limits' barrier weight μ (see above)
  double regularization = 1e-9;  ///< smallest ε of Q_uu + εI, relative to ‖Q_uu‖'s diagonal
  bool line_search = false;      ///< also in the updates (the start always searches)

  /// @brief Throws std::invalid_argument naming the first bad setting.
  void validate() const;
};

namespace detail {
/// @brief A LocalModel owned by value: copies clone it (so the solver copies as a whole).
class LocalModelHolder {
 public:
  LocalModelHolder() = default;
  explicit LocalModelHolder(std::unique_ptr<LocalModel> m) : p_(std::move(m)) {}
  LocalModelHolder(const LocalModelHolder& o) : p_(o.p_ ? o.p_->clone() : nullptr) {}
  LocalModelHolder& operator=(const LocalModelHolder& o) {
    if (this != &o) p_ = o.p_ ? o.p_->clone() : nullptr;
    return *this;
  }
  LocalModelHolder(LocalModelHolder&&) noexcept = default;
  LocalModelHolder& operator=(LocalModelHolder&&) noexcept = default;
  LocalModel* operator->() const { return p_.get(); }

 private:
  std::unique_ptr<LocalModel> p_;
};
}  // namespace detail

/// A solver copies with its problem, trajectory and workspaces (a warm start to replay from).
class RiccatiSolver final : public MpcSolver {
 public:
  /// @param problem the horizon's problem (its N stages; owned).
  /// @param Tf horizon length [s] (> 0), @param dt sampling period [s] (> 0).
  RiccatiSolver(OcpProblem problem, double Tf, double dt, const RiccatiSettings& settings);

  SolverKind kind() const override { return SolverKind::kRiccati; }
  OcpProblem& problem() override { return problem_; }
  const OcpProblem& problem() const override { return problem_; }
  double dt() const override { return dt_; }
  double initialize(double t, In q, In v) override;
  bool update(double t, In q, In v) override;
  const Vec& first_input() const override { return u0_; }
  const std::string& failure() const override { return failure_; }
  double residual_norm() const override { return kkt_; }
  double constraint_violation() const override { return violation_; }
  int evaluations() const override { return evaluations_; }
  const UpdateTimes& last_times() const override { return times_; }
  void enable_timing(bool on) override { timing_ = on; }
  void set_interrupt_check(std::function<void()> check) override { interrupt_check_ = std::move(check); }

  const RiccatiSettings& settings() const { return settings_; }
  double horizon() const { return Tf_; }
  /// @brief The current trajectory: states 2n × (N+1) (column 0 the last measured state), inputs
  /// (OcpProblem::input_dim) × N, and each stage's joint torques τ (n × N).
  const MatX<double>& states() const { return X_; }
  const MatX<double>& inputs() const { return U_; }
  const MatX<double>& torques() const { return T_; }
  /// @brief SQP iterations of the last update (or of the start).
  int iterations() const { return iterations_; }
  /// @brief The stage-0 gain of the last iteration in the input's coordinates, du_0 = K_0 dx_0
  /// (input_dim × 2n; ID under-actuated: the passive accelerations' part included).
  const MatX<double>& feedback_gain() const { return K0_; }
  /// @brief Warm start: the inputs U (input_dim × N); the states follow by a rollout from x_0 at
  /// the next update or start.
  void set_inputs(const MatX<double>& U);

  /// @brief One SQP iteration at time t from the measured x = (q, v), with or without a line
  /// search; returns the KKT residual at the iterate it started from.
  double iterate(double t, In q, In v, bool search);

 private:
  int n() const { return problem_.n(); }
  int N() const { return problem_.N(); }
  // stage i's QP as the recursion reads it (ID under-actuated: with the constraint eliminated)
  const StageLocal& qp(int i) const { return eliminate_ ? reduced_[static_cast<size_t>(i)] : stage_[static_cast<size_t>(i)]; }
  // ID under-actuated: stage i's null-space basis Z, Y_x, y_0 and its rewritten QP (see above)
  void eliminate(int i);
  // stage 0's input as joint values (FD under-actuated: zero on the passive joints)
  void set_first_input();
  double dtau() const { return Tf_ / N(); }
  // every stage's local model at the current trajectory, limits condensed, and the KKT residual
  void linearize(double t);
  // backward recursion with regularization ε; false if a Q_uu is not positive definite
  bool backward(double eps);
  // the QP's step (dX, dU) from the gains, then (dS, dZ)
  void forward();
  // the slope of bounded joint k's barrier at the torque reference u_ref (0 outside the limits)
  double recentering(int k, double u_ref) const;
  // the step length that keeps s and z positive
  double max_step(const MatX<double>& s, const MatX<double>& ds) const;
  // ℓ1 merit at trajectory + α·step (cost, barrier, constraint residuals); fills the trial trajectory
  double merit(double alpha, double nu);
  void take_step(double alpha, double alpha_dual);
  // the rollout from x_0 with the inputs U (start), slacks and multipliers from its torques
  void rollout_and_slacks(double t);
  // stage torques' distance outside the bounds
  double violation() const;
  // false (failure_ says why) where the iterates are non-finite or beyond 1e8, or, with
  // bound_residual, the KKT residual is. The start leaves the residual out: from its initial guess
  // on a fast unstable arm the costates, and so the residual, are that large (1e8 on a generated
  // arm whose open loop grows at 30 1/s) while the globalized iterations bring it down. (C/GMRES's
  // full-horizon start begins from this start's solution, Cgmres::initialize.)
  bool check_finite(bool bound_residual = true);

  OcpProblem problem_;
  RiccatiSettings settings_;
  double Tf_, dt_;
  detail::LocalModelHolder model_;
  std::vector<StageLocal> stage_;
  TerminalLocal terminal_;
  // inputs: nu_ rows in U_, nw_ in the recursion (ID under-actuated: the actuated accelerations)
  int nu_ = 0, nw_ = 0, ne_ = 0;
  bool eliminate_ = false;
  std::vector<int> passive_, actuated_;
  std::vector<StageLocal> reduced_;
  std::vector<MatX<double>> null_, Yx_;  ///< Z (n × n_u), Y_x (n × 2n) per stage
  MatX<double> y0_, qp_defect_;          ///< y_0 (n × N); the defects B y_0 + b (2n × N)
  MatX<double> Mee_, Meu_, Cx_, LZ_, T1_, K0_;
  Vec c_, nu_e_;
  std::vector<Eigen::LLT<MatX<double>>> llt_e_;  ///< M_EE per stage (eliminate), reused for ν
  double nu_max_ = 0;  ///< the largest |ν| of the last linearization
  // bounded joints: joint index, lower and upper torque, barrier weight μ per stage
  std::vector<int> joint_;
  Vec lower_, upper_, mu_;
  // trajectory: states, inputs, torques, slacks and multipliers (2m × N: upper rows first)
  MatX<double> X_, U_, T_, S_, Z_;
  // the QP's step and the trial point of the line search
  MatX<double> dX_, dU_, dS_, dZ_, Xt_, Ut_, St_;
  // recursion
  std::vector<MatX<double>> P_, K_;
  MatX<double> k_, p_, defect_;
  std::vector<Eigen::LLT<MatX<double>>> llt_;
  MatX<double> PA_, PB_, Qxx_, Quu_, Qux_;
  Vec pb_, qx_, qu_, W_, g_, lmd_, lmd_next_, Fi_, gu_, xn_, tau_, dtorque_;
  Vec u0_;
  Data hold_;              ///< RNEA of the start's holding torque
  bool rolled_out_ = false;  ///< whether the states are a trajectory of the inputs (else: roll out first)
  double kkt_ = 0, kkt_first_ = 0, violation_ = 0, regularization_ = 0;
  int iterations_ = 0, evaluations_ = 0;
  bool timing_ = false;
  std::function<void()> interrupt_check_;
  UpdateTimes times_;
  std::string failure_;
};

}  // namespace idmpc
