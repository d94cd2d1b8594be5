#pragma once
/// @file shooting.hpp
/// @brief The optimality residual of an OcpProblem (formulations.md) under both shooting schemes.
///
/// Single shooting: F(U, x) of the inputs U = (u_0 … u_{N−1}) or (a_0 … a_{N−1}), by an
/// explicit-Euler rollout from the measured state (eq. 12) and a backward costate sweep (eqs. 16,
/// 18, 22–24). Multiple shooting: the states x_1 … x_N and costates (λ, γ)_1 … (λ, γ)_N are
/// unknowns too; its residual (residual_at) is F_U together with the defects of the Euler state
/// and costate equations at those stored trajectories, every stage evaluated where it stands.
/// Condensing (Cgmres) runs the rollout and the costate sweep with given defects (residual with
/// `defects`): the trajectories they retrieve satisfy the state and costate equations up to
/// exactly those defects, so F_U there is a function of U alone and GMRES still runs on U.
///
/// With torque limits (formulations.md §Torque limits) each stage's block of U is (input, dummy inputs d, multipliers
/// ρ), and on an under-actuated model ID's adds the multipliers ν of the passive torques
/// (§Under-actuation): OcpProblem::stage_dim() long. FD's input on such a model is the actuators'
/// torques, scattered to the joints (the passive ones zero). The problem supplies the stage kernels; only the chaining of
/// stages lives here.

#include <memory>
#include <utility>

#include "idmpc/ocp/problem.hpp"
#include "idmpc/spatial/dual.hpp"

namespace idmpc {

/// @brief Wall-clock seconds spent in each part of the residual evaluations.
struct OcpTimes {
  double rollout = 0;  ///< forward sweep: dynamics along the horizon (ABA or RNEA), and what runs in lanes after it
  double costate = 0;  ///< backward sweep: derivatives/adjoints, costates and F
  long evaluations = 0;
};

/// @brief Defects of multiple shooting's state and costate equations (formulations.md §Multiple shooting), n × (N+1)
/// each. Column i of q, v (i = 0 … N−1): stage i's Euler state equation,
/// q_{i+1} − q_i − Δτ v_i and v_{i+1} − v_i − Δτ a_i. Column i of lmd, gmm: the costate equation,
/// λ_i − λ_{i+1} − Δτ ∂H_i/∂q and γ_i − γ_{i+1} − Δτ ∂H_i/∂v for i = 1 … N−1, λ_N − ∂φ/∂q and
/// γ_N − ∂φ/∂v for i = N. Unused columns (q, v: N; lmd, gmm: 0) are zero.
struct ShootingDefects {
  MatX<double> q, v, lmd, gmm;
  void resize(int n, int N);
  double squared_norm() const;
  /// @brief this = s·other
  void assign_scaled(const ShootingDefects& other, double s);
};

/// @brief Stored states and costates of multiple shooting, n × (N+1) each: columns 1 … N are
/// unknowns; column 0 of q, v is the measured state (set by each evaluation), of lmd, gmm unused.
struct ShootingTrajectory {
  MatX<double> q, v, lmd, gmm;
  void resize(int n, int N);
  bool all_finite() const;
  double max_abs() const;
};

class Shooting {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;

  explicit Shooting(OcpProblem problem);
  /// @brief The problem built in place (see OcpProblem's constructor).
  template <typename... Args>
  explicit Shooting(const Model& model, Args&&... args) : Shooting(OcpProblem(model, std::forward<Args>(args)...)) {}
  template <typename... Args>
  explicit Shooting(std::shared_ptr<const Model> model, Args&&... args)
      : Shooting(OcpProblem(std::move(model), std::forward<Args>(args)...)) {}

  int n() const { return problem_.n(); }
  int N() const { return problem_.N(); }
  /// @brief Unknowns of one stage (input, dummy inputs, multipliers: OcpProblem::stage_dim) and of
  /// U (N of them).
  int stage_dim() const { return problem_.stage_dim(); }
  int dim() const { return problem_.N() * problem_.stage_dim(); }
  OcpProblem& problem() { return problem_; }
  const OcpProblem& problem() const { return problem_; }
  Formulation formulation() const { return problem_.formulation(); }
  DerivativeMode derivative_mode() const { return problem_.derivative_mode(); }
  const OcpWeights& weights() const { return problem_.weights(); }

  /// @brief The time t of the horizon's start for the evaluations that follow: stage i's
  /// references are those at t + i·Δτ (OcpProblem::set_stage_times). Zero until set; matters
  /// only for references that move.
  void set_time(double t) { t_ = t; }
  double time() const { return t_; }

  /// @brief Single shooting: stacked optimality residual F(U, x) (size stages·stage_dim) of the
  /// problem with the first `stages` steps over a horizon of length T (Δτ = T/stages), from
  /// x = (q0, v0). With `defects` (full horizon only), the rollout and the costate sweep add
  /// them: q_{i+1} = q_i + Δτ v_i + e.q_i, …, λ_N = ∂φ/∂q + e.lmd_N, λ_i = λ_{i+1} + Δτ ∂H_i/∂q
  /// + e.lmd_i (the condensed residual of multiple shooting). Fills trajectory().
  void residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F, int stages,
                const ShootingDefects* defects = nullptr);
  /// @brief Residual of the full N-stage problem.
  void residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F, const ShootingDefects* defects = nullptr) {
    residual(U, q0, v0, T, F, N(), defects);
  }

  /// @brief The residual of the full horizon and its exact directional derivative along W:
  /// F = residual(U, q0, v0, T, defects) and dF = (∂F/∂U)·W at fixed state, time and defects,
  /// by one evaluation in dual numbers (formulations.md §Exact products): the same stage arithmetic, stage by stage,
  /// each operation carrying its tangent. No increment, no cancellation: dF is exact up to
  /// rounding. Needs enable_exact_products (std::logic_error otherwise); allocation-free after
  /// it. Fills trajectory() with the values.
  void residual_and_product(In U, In W, In q0, In v0, double T, Eigen::Ref<Vec> F, Eigen::Ref<Vec> dF,
                            const ShootingDefects* defects = nullptr);
  /// @brief The tangents of the states and costates of the last residual_and_product: their
  /// derivatives along W (column 0 of q, v zero).
  const ShootingTrajectory& trajectory_tangent() const { return dx_; }
  /// @brief Sizes what residual_and_product needs (dual-number stage workspaces and trajectories).
  void enable_exact_products();
  bool exact_products() const { return dual_.F.size() > 0; }

  /// @brief Multiple shooting: F_U (size dim) and the defects of the stored states and costates
  /// `at` (columns 1 … N) with x_0 = (q0, v0) measured, horizon T. Every stage is evaluated at
  /// its stored state, independently of the others (in SIMD lanes: ID with adjoints, and FD with
  /// adjoints, whose stages are independent here at the stored costates too). Fills
  /// trajectory() with `at`. With zero defects, F equals residual(U, q0, v0, T).
  void residual_at(In U, const ShootingTrajectory& at, In q0, In v0, double T, Eigen::Ref<Vec> F,
                   ShootingDefects& defects);

  /// @brief States and costates of the last evaluation (columns 0 … stages; λ_0, γ_0 unset).
  const ShootingTrajectory& trajectory() const { return x_; }
  /// @brief Acceleration a_0 and torque u_0 of the first stage of the last residual evaluation.
  Eigen::Ref<const Vec> first_acceleration() const { return a_.col(0); }
  Eigen::Ref<const Vec> first_torque() const { return u_.col(0); }
  /// @brief Torques u_i (n × N) of the stages of the last residual evaluation.
  const MatX<double>& torques() const { return u_; }

  /// @brief Stages in SIMD lanes wherever they are independent (OcpProblem::set_stages_in_lanes):
  /// ID's stage dynamics and products; FD matrix's stage derivatives; FD adjoint's stages at stored
  /// costates (multiple shooting only).
  void set_stage_batching(bool on) { problem_.set_stages_in_lanes(on); }
  /// @brief Whether single shooting's residual runs stages in lanes (ID, FD matrix); FD adjoint's
  /// costate lanes are OcpProblem::costate_lanes().
  bool stage_batching() const { return problem_.stages_in_lanes() || problem_.derivative_lanes(); }

  /// @brief Accumulated timing of residual evaluations (off unless enabled).
  void enable_timing(bool on) { timing_ = on; }
  const OcpTimes& times() const { return times_; }
  void reset_times() { times_ = OcpTimes{}; }

 private:
  /// the horizon's trajectories of one evaluation in scalar S: states and costates n × (N+1),
  /// accelerations and torques n × N, dummy inputs and multipliers m × N, ∂H/∂q and ∂H/∂v
  template <typename S> struct Sweep {
    MatX<S>& q;
    MatX<S>& v;
    MatX<S>& lmd;
    MatX<S>& gmm;
    MatX<S>& a;
    MatX<S>& u;
    MatX<S>& d;
    MatX<S>& rho;
    VecX<S>& hq;
    VecX<S>& hv;
  };
  /// the buffers of the dual-number evaluations
  struct DualBuffers {
    MatX<Dual> q, v, lmd, gmm, a, u, d, rho;
    VecX<Dual> hq, hv, U, q0, v0, F;
  };

  // single shooting's forward and backward sweeps (residual, residual_and_product) in scalar S
  template <typename S>
  void sweep(Sweep<S> x, const Eigen::Ref<const VecX<S>>& U, const Eigen::Ref<const VecX<S>>& q0,
             const Eigen::Ref<const VecX<S>>& v0, double T, Eigen::Ref<VecX<S>> F, int stages,
             const ShootingDefects* e);
  // U's stage blocks into the input, d and ρ columns
  template <typename S> void unpack(Sweep<S>& x, const Eigen::Ref<const VecX<S>>& U, int stages) const;
  // the horizon's trajectories, columns 0 … stages − 1, for the problem's calls across stages
  StageTrajectories trajectories(int stages, const MatX<double>* gmm) {
    return StageTrajectories{stages, x_.q, x_.v, a_, u_, rho_, gmm};
  }

  OcpProblem problem_;
  double t_ = 0;
  bool timing_ = false;
  OcpTimes times_;
  ShootingTrajectory x_;     ///< states and costates, n × (N+1)
  MatX<double> a_, u_;       ///< n × N accelerations and torques
  MatX<double> d_, rho_;     ///< m × N dummy inputs, (m + n_e) × N multipliers (ρ, ν)
  Vec hq_, hv_, phi_q_, phi_v_;  ///< ∂H/∂q, ∂H/∂v; terminal gradient
  DualBuffers dual_;             ///< enable_exact_products
  ShootingTrajectory dx_;        ///< trajectory_tangent
};

}  // namespace idmpc
