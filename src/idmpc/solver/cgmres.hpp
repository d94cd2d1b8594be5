#pragma once
/// @file cgmres.hpp
/// @brief Continuation/GMRES (Ohtsuka 2004, formulations.md §C/GMRES, §Multiple shooting), one solver for every problem and
/// both shooting schemes:
/// Ḟ = −ζF is tracked by solving (∂F/∂U) U̇ = −ζF − (∂F/∂x)ẋ − ∂F/∂t with matrix-free
/// products (forward differences, the paper's way, or exact ones in dual numbers: Products) and
/// kmax GMRES iterations, then U ← U + Δt U̇.
///
/// Multiple shooting (as in Ohtsuka's and autogenu's multiple-shooting C/GMRES): the states and
/// costates of stages 1 … N are unknowns too, and all residuals — F_U and the defects E of the
/// state and costate equations — follow Ḟ = −ζF. Condensing: for a direction W, the state and
/// costate directions are those that make the defects decay, Ė = −ζE; by forward difference,
/// the trajectories retrieved from (U + hW, x + hẋ, t + h) with the defects (1 − hζ)E
/// (Shooting::residual with defects). So F_U is a function G of U alone and GMRES runs on U:
///   b = −ζG − [G(U, x + hẋ, t + h; (1 − hζ)E) − G(U, x, t; E)] / h,
///   A W = [G(U + hW, x + hẋ, t + h; (1 − hζ)E) − G(U, x + hẋ, t + h; (1 − hζ)E)] / h,
/// and the stored trajectories move by Δt·(retrieved at U + hU̇ − stored)/h: one evaluation more
/// per update than single shooting. With E = 0 and the stored trajectories those of the rollout,
/// the two schemes take the same step.

#include <functional>
#include <string>

#include "idmpc/solver/gmres.hpp"
#include "idmpc/solver/horizon.hpp"
#include "idmpc/solver/mpc_solver.hpp"
#include "idmpc/solver/shooting.hpp"

namespace idmpc {

/// @brief How the horizon's stages are chained (formulations.md §Multiple shooting).
enum class ShootingScheme { kSingle, kMultiple };
/// @brief "single"/"multiple"; parse throws std::invalid_argument naming the value.
std::string to_string(ShootingScheme s);
ShootingScheme parse_shooting(const std::string& s);

/// @brief How C/GMRES forms its products (∂F/∂U)·W (formulations.md §Exact products): by the paper's forward
/// difference [F(U + hW) − F(U)]/h, or exactly, by one evaluation in dual numbers
/// (Shooting::residual_and_product).
enum class Products { kDifference, kExact };
/// @brief "difference"/"exact"; parse throws std::invalid_argument naming the value.
std::string to_string(Products p);
Products parse_products(const std::string& s);

/// @brief ‖F‖ at or below which a full-horizon start counts as solved (Cgmres::initialize: above
/// it the continuation from zero is tried too). A C/GMRES loop runs at residuals of 1e-3–1; a start
/// above this one begins the loop away from the optimum it is meant to track.
inline constexpr double kStartSolved = 1e-4;

struct CgmresSettings {
  int kmax = 10;
  ShootingScheme shooting = ShootingScheme::kSingle;
  /// @brief The GMRES products (and those of the full-horizon start). The right-hand side's
  /// (∂F/∂x)ẋ + ∂F/∂t stays a forward difference with either.
  Products products = Products::kDifference;
  double Tf = 0.5;
  double alpha = 1.0;
  double dt = 1e-3;    ///< sampling period Δt
  double zeta = 0;     ///< stabilization ζ; 0 means 1/Δt
  double h = 1e-8;     ///< forward-difference increment
  int init_iterations = 50;
  double init_tolerance = 1e-10;
  /// @brief At a time whose horizon is open (T(t) > 0, e.g. α = 0), initialize solves the
  /// full N-stage problem (see Cgmres::initialize) instead of copying the one-stage solution.
  bool init_full_horizon = false;

  /// @brief Throws std::invalid_argument naming the first bad setting.
  void validate() const;
};

class Cgmres {
 public:
  Cgmres(Shooting& ocp, const CgmresSettings& settings);

  /// @brief Zero-horizon initialization at time t: Newton on the one-stage problem F_0 = 0
  /// (every stage sees x), copied to all stages. With torque limits, Newton first on the input
  /// alone (ρ = 0), then on the whole stage block from (d, ρ) consistent with that input's
  /// torque. With settings.init_full_horizon and T(t) > 0 the full problem is solved first by
  /// the Riccati solver (riccati.hpp: Gauss–Newton SQP with a line search on the cost, on the
  /// same OcpProblem), its inputs then polished by damped Newton–GMRES on F with (d, ρ)
  /// consistent with their torques. If that leaves ‖F‖ above 1e-4, the one-stage solution at
  /// T = 0 starts a continuation instead: the horizon grown to T(t) in kInitHorizonSteps, then
  /// (with limits) the dummy weight brought down from 10⁴ × nominal, each level solved by damped
  /// Newton–GMRES keeping d, ρ > 0; the better of the two is kept. Returns ‖F‖ reached (one
  /// stage, or all N stages). Under
  /// multiple shooting the stored trajectories are then those of the solution's rollout (zero
  /// defects): both schemes start from the same point.
  double initialize(double t, const Eigen::Ref<const VecX<double>>& q,
                    const Eigen::Ref<const VecX<double>>& v);

  /// @brief One C/GMRES update at time t from the measured (q, v). Returns false if the
  /// solution or the residual became non-finite or blew up (divergence). With torque limits,
  /// the dummy inputs and multipliers are first made consistent with the stage torques at the
  /// measured state (TorqueBounds::consistent_dummy, their rates zeroed): one more evaluation
  /// of F. Without that, d collapses to 0 with ρ → ∞ on joints far from their bounds within
  /// 0.1–1 s on the Panda reach (a singular point of the constraint), and the loop diverges.
  bool update(double t, const Eigen::Ref<const VecX<double>>& q,
              const Eigen::Ref<const VecX<double>>& v);

  /// @brief One Newton–GMRES step on the problem frozen at (t, x), under the configured scheme:
  /// the update with ẋ = 0, no time derivative and ζ = 1/Δt (a full step), and (d, ρ) left as
  /// they are (not made consistent with the torques, which would undo the step on them).
  /// Returns false on divergence, as update.
  bool newton_step(double t, const Eigen::Ref<const VecX<double>>& q,
                   const Eigen::Ref<const VecX<double>>& v);

  /// @brief Why the last update returned false (empty after a good one).
  const std::string& failure() const { return failure_; }
  const VecX<double>& solution() const { return U_; }
  /// @brief Warm start: the solution U (size Shooting::dim), its rate zeroed.
  void set_solution(const Eigen::Ref<const VecX<double>>& U);
  /// @brief Multiple shooting: the stored states and costates (columns 1 … N are the unknowns).
  const ShootingTrajectory& trajectory() const { return X_; }
  void set_trajectory(const ShootingTrajectory& X);
  /// @brief Multiple shooting: the defects of the stored trajectories at the start of the last
  /// update (zero under single shooting).
  const ShootingDefects& defects() const { return E_; }
  const VecX<double>& solution_rate() const { return Udot_; }
  /// @brief ‖F(U, x, t)‖ at the start of the last update (the optimality error of the solution
  /// being tracked, at the measured state); under multiple shooting ‖(F_U, E)‖.
  double residual_norm() const { return residual_norm_; }
  /// @brief With torque limits: how far the stage torques of the solution being tracked leave
  /// their bounds at the start of the last update, TorqueBounds::violation [N m] (0 without).
  double constraint_violation() const { return constraint_violation_; }
  int gmres_iterations() const { return iterations_; }
  /// @brief F evaluations in the last update (kmax + 3 unless GMRES stopped early; one more
  /// with torque limits, one more under multiple shooting).
  int evaluations() const { return evaluations_; }
  const UpdateTimes& last_times() const { return times_; }
  void enable_timing(bool on) { timing_ = on; ocp_.enable_timing(on); }
  /// @brief Called before every Newton iteration of initialize (MpcSolver::set_interrupt_check).
  void set_interrupt_check(std::function<void()> check) { interrupt_check_ = std::move(check); }
  const CgmresSettings& settings() const { return settings_; }
  const Shooting& ocp() const { return ocp_; }
  double horizon(double t) const { return horizon_.length(t); }

 private:
  double solve_full_horizon(const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                            double T, bool continuation = true);
  // the full-horizon start from the Riccati solver's solution, polished by Newton–GMRES; ‖F‖
  // reached (infinite if that solver's start diverged)
  double start_from_riccati(double t, const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                            double T);
  void synchronize_dummy();
  // the update at (t, x); frozen: newton_step
  bool step(double t, const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v, bool frozen);
  // F at the measured state under the scheme (multiple: also the defects E_)
  void evaluate(const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v, double T);
  bool multiple() const { return settings_.shooting == ShootingScheme::kMultiple; }

  Shooting& ocp_;
  CgmresSettings settings_;
  Horizon horizon_;
  Gmres gmres_;
  bool timing_ = false;
  std::function<void()> interrupt_check_;
  VecX<double> U_, Udot_, F_, Fx_, Fw_, Uw_, b_, qh_, vh_, a0_;
  ShootingTrajectory X_;    ///< multiple shooting: stored states and costates
  ShootingDefects E_, Eh_;  ///< their defects at the measured state, and (1 − hζ)E
  double residual_norm_ = 0;
  double constraint_violation_ = 0;
  std::string failure_;
  int iterations_ = 0;
  int evaluations_ = 0;
  UpdateTimes times_;
};

}  // namespace idmpc
