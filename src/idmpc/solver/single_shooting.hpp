#pragma once
/// @file single_shooting.hpp
/// @brief Single shooting of an OcpProblem (DESIGN §4): the stacked optimality residual
/// F(U, x) of the inputs U = (u_0 … u_{N−1}) or (a_0 … a_{N−1}), by an explicit-Euler rollout
/// from the measured state (eq. 12) and a backward costate sweep (eqs. 16, 18, 22–24). With
/// torque limits (DESIGN §8) each stage's block of U is (input, dummy inputs d, multipliers ρ),
/// OcpProblem::stage_dim() long. The problem supplies the stage kernels; only the chaining of
/// stages lives here.

#include <utility>

#include "idmpc/ocp/problem.hpp"

namespace idmpc {

/// @brief Wall-clock seconds spent in each part of the residual evaluations.
struct OcpTimes {
  double rollout = 0;  ///< forward sweep: dynamics along the horizon (ABA or RNEA)
  double costate = 0;  ///< backward sweep: derivatives/adjoints, costates and F
  long evaluations = 0;
};

class SingleShooting {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;

  explicit SingleShooting(OcpProblem problem);
  /// @brief The problem built in place (see OcpProblem's constructor).
  template <typename... Args>
  explicit SingleShooting(const Model& model, Args&&... args)
      : SingleShooting(OcpProblem(model, std::forward<Args>(args)...)) {}

  int n() const { return problem_.n(); }
  int N() const { return problem_.N(); }
  /// @brief Unknowns of one stage (n + 2m: input, dummy inputs, multipliers) and of U (N of them).
  int stage_dim() const { return problem_.stage_dim(); }
  int dim() const { return problem_.N() * problem_.stage_dim(); }
  OcpProblem& problem() { return problem_; }
  const OcpProblem& problem() const { return problem_; }
  Formulation formulation() const { return problem_.formulation(); }
  DerivativeMode derivative_mode() const { return problem_.derivative_mode(); }
  const OcpWeights& weights() const { return problem_.weights(); }

  /// @brief Stacked optimality residual F(U, x) (size stages·stage_dim) of the problem with the first
  /// `stages` steps over a horizon of length T (Δτ = T/stages), from x = (q0, v0).
  /// Fills the trajectories (q, v, a, u) of the first `stages` steps.
  void residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F, int stages);
  /// @brief Residual of the full N-stage problem.
  void residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F) { residual(U, q0, v0, T, F, N()); }

  /// @brief Acceleration a_0 and torque u_0 of the first stage of the last residual evaluation.
  Eigen::Ref<const Vec> first_acceleration() const { return a_.col(0); }
  Eigen::Ref<const Vec> first_torque() const { return u_.col(0); }
  /// @brief Torques u_i (n × N) of the stages of the last residual evaluation.
  const MatX<double>& torques() const { return u_; }

  /// @brief ID with adjoints only: stages in SIMD lanes (OcpProblem::set_stages_in_lanes).
  void set_stage_batching(bool on) { problem_.set_stages_in_lanes(on); }
  bool stage_batching() const { return problem_.stages_in_lanes(); }

  /// @brief Accumulated timing of residual evaluations (off unless enabled).
  void enable_timing(bool on) { timing_ = on; }
  const OcpTimes& times() const { return times_; }
  void reset_times() { times_ = OcpTimes{}; }

 private:
  OcpProblem problem_;
  bool timing_ = false;
  OcpTimes times_;
  MatX<double> q_, v_, a_, u_;                    ///< n × (N+1) states, n × N inputs
  MatX<double> d_, rho_;                          ///< m × N dummy inputs and multipliers
  Vec lmd_, gmm_, lmd_next_, gmm_next_, hq_, hv_;  ///< costates λ, γ (running), ∂H/∂q, ∂H/∂v
};

}  // namespace idmpc
