#pragma once
/// @file cgmres.hpp
/// @brief Continuation/GMRES (Ohtsuka 2004, DESIGN §6), one solver for every problem
/// (single shooting):
/// Ḟ = −ζF is tracked by solving (∂F/∂U) U̇ = −ζF − (∂F/∂x)ẋ − ∂F/∂t with matrix-free
/// forward-difference products and kmax GMRES iterations, then U ← U + Δt U̇.

#include <string>

#include "idmpc/solver/gmres.hpp"
#include "idmpc/solver/horizon.hpp"
#include "idmpc/solver/single_shooting.hpp"

namespace idmpc {

struct CgmresSettings {
  int kmax = 10;
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

/// @brief Wall-clock split of one update [s].
struct UpdateTimes {
  double total = 0;
  double rollout = 0;  ///< forward sweeps of the F evaluations (dynamics)
  double costate = 0;  ///< backward sweeps (derivatives/adjoints, costates)
  double gmres = 0;    ///< everything else: Arnoldi, rotations, vector updates
};

class Cgmres {
 public:
  Cgmres(SingleShooting& ocp, const CgmresSettings& settings);

  /// @brief Zero-horizon initialization at time t: Newton on the one-stage problem F_0 = 0
  /// (every stage sees x), copied to all stages. With torque limits, Newton first on the input
  /// alone (ρ = 0), then on the whole stage block from (d, ρ) consistent with that input's
  /// torque. With settings.init_full_horizon and T(t) > 0, that one-stage solution at T = 0
  /// starts a continuation: the horizon grown to T(t) in kInitHorizonSteps, then (with limits)
  /// the dummy weight brought down from 10⁴ × nominal, each level solved by damped
  /// Newton–GMRES keeping d, ρ > 0. Returns ‖F‖ reached (one stage, or all N stages).
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

  /// @brief Why the last update returned false (empty after a good one).
  const std::string& failure() const { return failure_; }
  const VecX<double>& solution() const { return U_; }
  const VecX<double>& solution_rate() const { return Udot_; }
  /// @brief ‖F(U, x, t)‖ at the start of the last update (the optimality error of the solution
  /// being tracked, at the measured state).
  double residual_norm() const { return residual_norm_; }
  /// @brief With torque limits: how far the stage torques of the solution being tracked leave
  /// their bounds at the start of the last update, TorqueBounds::violation [N m] (0 without).
  double constraint_violation() const { return constraint_violation_; }
  int gmres_iterations() const { return iterations_; }
  /// @brief F evaluations in the last update (kmax + 3 unless GMRES stopped early; kmax + 4
  /// with torque limits).
  int evaluations() const { return evaluations_; }
  const UpdateTimes& last_times() const { return times_; }
  void enable_timing(bool on) { timing_ = on; ocp_.enable_timing(on); }
  const CgmresSettings& settings() const { return settings_; }
  const SingleShooting& ocp() const { return ocp_; }
  double horizon(double t) const { return horizon_.length(t); }

 private:
  double solve_full_horizon(const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                            double T);
  void synchronize_dummy();

  SingleShooting& ocp_;
  CgmresSettings settings_;
  Horizon horizon_;
  Gmres gmres_;
  bool timing_ = false;
  VecX<double> U_, Udot_, F_, Fx_, Fw_, Uw_, b_, qh_, vh_, a0_;
  double residual_norm_ = 0;
  double constraint_violation_ = 0;
  std::string failure_;
  int iterations_ = 0;
  int evaluations_ = 0;
  UpdateTimes times_;
};

}  // namespace idmpc
