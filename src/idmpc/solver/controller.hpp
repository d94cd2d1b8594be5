#pragma once
/// @file controller.hpp
/// @brief The NMPC controller of the paper's closed loop: the problem, its shooting
/// residual, the C/GMRES solver and the torque rule of eqs. 27–28, in one place.
///
/// Timing (formulations.md §The torque rule): the update made at time t from the measured x(t) yields the torque
/// applied over [t + Δt, t + 2Δt), i.e. one sampling period later; the torque of the
/// zero-horizon solution at t = 0 is applied over the first period.
///   FD: τ = u_0 of the new solution (â_0 is not used).
///   ID: τ = ID(q + Δt v, v + Δt â_0, a_0) − d̂, a_0 from the new solution and â_0 the a_0 of
///       the previous one, which the plant is executing while the controller computes.
///
/// Offset-free tracking (formulations.md §Disturbance observer), off unless enabled: a disturbance observer estimates the
/// joint torque d̂ the model misses from each measured velocity change,
///   d̂ ← (1 − β) d̂ + β (ID(q⁻, v⁻, (v − v⁻)/Δt) − τ⁻),   β = min(1, Δt / T_obs),
/// with (q⁻, v⁻) the previous measurement, Δt the time since it (the control period, or the
/// interval given to update) and τ⁻ the torque applied over [t − Δt, t) (known from the timing
/// above), and hands it to both formulations' horizon model (OcpProblem::set_disturbance).

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "idmpc/model/data.hpp"
#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/cgmres_mpc.hpp"
#include "idmpc/solver/controller_settings.hpp"
#include "idmpc/solver/horizon_setup.hpp"
#include "idmpc/solver/riccati.hpp"
#include "idmpc/solver/shooting.hpp"

namespace idmpc {

class Controller {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;

  /// @brief The controller of `model` (the robot's rigid-body model; the plant's passive forces it
  /// lacks are settings) with `settings`, their "auto" choices made (horizon_setup()). Shares the
  /// models, owns the problem and the solver. Throws std::invalid_argument naming the first bad
  /// setting.
  Controller(std::shared_ptr<const Model> model, const ControllerSettings& settings);

  /// @brief From a problem built by hand: owns it and the solver (C/GMRES with `settings`); the
  /// returned torques are clamped to the problem's torque bounds (set_torque_limits to clamp
  /// otherwise). `plant_model` is the model of the ID torque rule and the observer; null: the
  /// problem's model.
  Controller(OcpProblem problem, const CgmresSettings& settings,
             std::shared_ptr<const Model> plant_model = nullptr);
  /// @brief From a solver built by hand (CgmresMpc, RiccatiSolver, or one of your own), as above.
  explicit Controller(std::unique_ptr<MpcSolver> solver, std::shared_ptr<const Model> plant_model = nullptr);
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;
  /// @brief A controller moves with what it owns (solver, problem, workspaces); the models stay shared.
  Controller(Controller&&) noexcept = default;
  Controller& operator=(Controller&&) noexcept = default;
  ~Controller() = default;

  /// @brief The models and weights chosen for the settings (horizon_setup.hpp) and why; null for a
  /// controller built from a problem or a solver.
  const HorizonSetup* horizon_setup() const { return setup_.get(); }
  int n() const { return solver_->problem().n(); }
  double dt() const { return solver_->dt(); }
  const OcpProblem& problem() const { return solver_->problem(); }
  OcpProblem& problem() { return solver_->problem(); }
  const VecX<double>& q_ref() const { return problem().cost().q_ref(); }
  /// @brief The solver, whatever its family.
  MpcSolver& solver() { return *solver_; }
  const MpcSolver& solver() const { return *solver_; }
  SolverKind solver_kind() const { return solver_->kind(); }
  /// @brief C/GMRES's shooting residual and solver; std::logic_error under another solver.
  Shooting& nlp();
  const Shooting& nlp() const;
  Cgmres& cgmres();
  const Cgmres& cgmres() const;

  /// @brief Zero-horizon initialization from the measured x(0) = (q, v). Returns τ(0), the
  /// torque to apply over the first sampling period. If the initialization's residual or
  /// torque is non-finite, failure() says so and the torque is zero (nothing to apply).
  const Vec& initialize(In q, In v);

  /// @brief One control update at time t from the measured (q, v). On success returns true
  /// and torque() is τ(t + Δt); on divergence returns false and failure() says why.
  bool update(double t, In q, In v);

  /// @brief One control update in a loop whose torques arrive late (compute latency, formulations.md
  /// §Compute latency): as update(t, q, v), but the observer learns what the plant did since the previous
  /// measurement, `interval` seconds (> 0) under the mean torque `tau_applied`, instead of
  /// assuming one period under the previous update's torque.
  bool update(double t, In q, In v, double interval, In tau_applied);

  /// @brief After a successful update: aims its torque at the instant it reaches the plant,
  /// `delay` seconds (>= 0) after its measurement: eqs. 27–28 predict the state over `delay` instead of Δt. The
  /// rule stays the formulation's own: ID's ID(q + delay·v, v + delay·â_0, a_0) − d̂ moves with
  /// the delay, FD's u_0 has no prediction to move. torque() and commanded_torque() change
  /// (clamped as always); returns false with failure() for a non-finite torque.
  bool aim(double delay);

  /// @brief A function initialize calls between the iterations of its start, which may throw to
  /// abandon a long start (MpcSolver::set_interrupt_check); empty: none.
  void set_interrupt_check(std::function<void()> check) { solver_->set_interrupt_check(std::move(check)); }

  /// @brief Actuator limits: every torque the controller returns lies in [lower, upper]
  /// (±infinity: unbounded). May tighten the clamp within the horizon's bounds at any time (an
  /// actuator derated while running); throws std::invalid_argument for sizes other than n, NaN,
  /// lower ≥ upper, or a joint the horizon bounds (OcpProblem's torque limits) with limits
  /// beyond those bounds.
  void set_torque_limits(const Vec& lower, const Vec& upper);

  /// @brief A new target q_ref from the next update on (the torque reference ID(q_ref, 0, 0)
  /// follows). Size n, finite; allocation-free.
  void set_target(const Vec& q_ref);
  /// @brief A new pose for the frame target from the next update on (ControllerSettings::
  /// frame_target needed; a frame reference, if any, keeps moving the position). Allocation-free.
  void set_frame_target(const Vec3<double>& position, const Mat3<double>& rotation) {
    problem().set_frame_pose(position, rotation);
  }
  const Vec& torque_lower() const { return lower_; }
  const Vec& torque_upper() const { return upper_; }

  /// @brief Turns the disturbance observer on with time constant T_obs [s] (β = min(1, Δt/T_obs)),
  /// or off with 0. Takes effect at the next update: switched on, d̂ learns from the next
  /// measurement on; switched off, d̂ holds its last estimate (the horizon and the ID rule keep
  /// using it) until initialize sets it to zero. Off from the start, d̂ stays 0. Throws
  /// std::invalid_argument for a negative or non-finite value.
  void set_disturbance_observer(double time_constant);
  double disturbance_observer() const { return observer_time_constant_; }
  /// @brief The current estimate d̂ (zero after initialize; held while the observer is off).
  const Vec& disturbance() const { return problem().disturbance(); }

  /// @brief The torque of the last initialize/update, within the limits: what the plant gets.
  const Vec& torque() const { return tau_; }
  /// @brief The torque the rule commanded before clamping to the limits.
  const Vec& commanded_torque() const { return tau_cmd_; }
  /// @brief Whether the last torque was clamped on joint j.
  bool saturated(int j) const { return tau_[j] != tau_cmd_[j]; }
  /// @brief â_0: the first-stage acceleration of the solution the plant is executing (ID;
  /// zero in FD, whose rule does not use it).
  const Vec& applied_acceleration() const { return a0_hat_; }
  const std::string& failure() const { return failure_; }
  double residual_norm() const { return solver_->residual_norm(); }
  /// @brief The solver's residual when the last initialize returned (NaN if it failed).
  double start_residual() const { return start_residual_; }
  /// @brief The task's stage cost (StageTerms::stage_cost) of a measured state and the torque
  /// applied from it, at the references of the last update's time: what a closed loop
  /// integrates to compare controllers by their outcome.
  double stage_cost(In q, In v, In u) const { return problem().stage_cost(0, q, v, u); }
  /// @brief MpcSolver::constraint_violation of the last update [N m].
  double constraint_violation() const { return solver_->constraint_violation(); }

 private:
  // eqs. 27–28: τ from the current solution, measured (q, v) and â_0 (all given), then
  // clamped to the actuator limits
  void torque_rule(In q, In v, In a0_hat, double dt);
  // the observer's step from the previous measurement to (q, v), `interval` later, the plant
  // having applied `tau_applied` in between
  void observe(In q, In v, double interval, In tau_applied);
  // the torque rule's checks and bookkeeping after a successful solve
  bool finish_update(In q, In v);
  // the clamp [lower, upper], checked; with match_horizon, equal to the horizon's bounds where it has any
  void check_and_set_clamp(const Vec& lower, const Vec& upper, bool match_horizon);

  // from the settings and the choices made for them
  Controller(const ControllerSettings& settings, std::shared_ptr<const HorizonSetup> setup);

  std::unique_ptr<MpcSolver> solver_;
  std::shared_ptr<const HorizonSetup> setup_;  ///< null when built from a problem or a solver
  std::shared_ptr<const Model> plant_model_;  ///< for the ID torque and the observer
  Data data_;                 ///< for the ID torque
  Vec tau_, tau_cmd_, a0_hat_, q_pred_, v_pred_, lower_, upper_;
  // the last update's measurement and the â_0 its torque rule used (aim re-runs the rule)
  Vec q_meas_, v_meas_, a0_rule_;
  // observer: time constant (0: off), previous measurement, torques over the last and the
  // current period, the estimate and a scratch acceleration
  double observer_time_constant_ = 0;
  bool have_previous_ = false;
  Vec q_prev_, v_prev_, tau_last_, tau_pending_, d_hat_, a_meas_;
  double start_residual_ = std::numeric_limits<double>::quiet_NaN();
  std::string failure_;
};

}  // namespace idmpc
