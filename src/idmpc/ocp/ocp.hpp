#pragma once
/// @file ocp.hpp
/// @brief The two discretized optimal control problems of DESIGN §4 behind one interface:
/// forward dynamics (U = torques u_0…u_{N−1}) and inverse dynamics (U = accelerations
/// a_0…a_{N−1}, paper eqs. 12, 16, 18, 22–25), each with derivatives by full matrices (the
/// paper's way) or by O(n) adjoint sweeps (DESIGN §5). One rollout/costate skeleton serves all
/// four; only the stage kernels differ.

#include <chrono>
#include <string>
#include <vector>

#include "idmpc/model/data.hpp"
#include "idmpc/spatial/pack.hpp"

namespace idmpc {

enum class Formulation { kForwardDynamics, kInverseDynamics };
enum class DerivativeMode { kMatrix, kAdjoint };

/// @brief "fd"/"id" and "matrix"/"adjoint"; parse throws std::invalid_argument naming the value.
std::string to_string(Formulation f);
std::string to_string(DerivativeMode d);
Formulation parse_formulation(const std::string& s);
DerivativeMode parse_derivative_mode(const std::string& s);

/// @brief Diagonal weights of the costs (paper eqs. 32–34), each of size n.
struct OcpWeights {
  VecX<double> Qq, Qv, Qa, R;
};

/// @brief Wall-clock seconds spent in each part of the residual evaluations.
struct OcpTimes {
  double rollout = 0;  ///< forward sweep: dynamics along the horizon (ABA or RNEA)
  double costate = 0;  ///< backward sweep: derivatives/adjoints, costates and F
  long evaluations = 0;
};

class Ocp {
 public:
  /// @param N horizon steps (≥ 1); weights of size model.n; q_ref of size model.n.
  Ocp(const Model& model, Formulation formulation, DerivativeMode mode, OcpWeights weights,
      VecX<double> q_ref, int N);

  int n() const { return model_.n; }
  int N() const { return N_; }
  int dim() const { return N_ * model_.n; }
  Formulation formulation() const { return formulation_; }
  DerivativeMode derivative_mode() const { return mode_; }
  const OcpWeights& weights() const { return weights_; }

  /// @brief Stacked optimality residual F(U, x) (size stages·n) of the problem with the first
  /// `stages` steps over a horizon of length T (Δτ = T/stages), from x = (q0, v0).
  /// Fills the trajectories (q, v, a, u) of the first `stages` steps.
  void residual(const Eigen::Ref<const VecX<double>>& U, const Eigen::Ref<const VecX<double>>& q0,
                const Eigen::Ref<const VecX<double>>& v0, double T, Eigen::Ref<VecX<double>> F,
                int stages);
  /// @brief Residual of the full N-stage problem.
  void residual(const Eigen::Ref<const VecX<double>>& U, const Eigen::Ref<const VecX<double>>& q0,
                const Eigen::Ref<const VecX<double>>& v0, double T, Eigen::Ref<VecX<double>> F) {
    residual(U, q0, v0, T, F, N_);
  }

  /// @brief Acceleration a_0 and torque u_0 of the first stage of the last residual evaluation.
  Eigen::Ref<const VecX<double>> first_acceleration() const { return a_.col(0); }
  Eigen::Ref<const VecX<double>> first_torque() const { return u_.col(0); }

  /// @brief Torque to apply given the measured (q, v), the current solution U and â_0 (the
  /// previous update's a_0): FD applies u_0; ID applies ID(q + Δt v, v + Δt â_0, a_0)
  /// (paper eqs. 27–28 with t_app = t + Δt).
  void applied_torque(const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                      const Eigen::Ref<const VecX<double>>& U,
                      const Eigen::Ref<const VecX<double>>& a0_previous, double dt,
                      Eigen::Ref<VecX<double>> tau);

  /// @brief ID with adjoints only: evaluate the stage dynamics of kStageLanes stages at once in
  /// SIMD lanes (the ID rollout is linear in U and its adjoints do not depend on the costates,
  /// so all stages are independent). On by default; off evaluates stage by stage.
  void set_stage_batching(bool on) { batched_ = on && batchable(); }
  bool stage_batching() const { return batched_; }

  /// @brief Accumulated timing of residual evaluations (off unless enabled).
  void enable_timing(bool on) { timing_ = on; }
  const OcpTimes& times() const { return times_; }
  void reset_times() { times_ = OcpTimes{}; }

 private:
  bool batchable() const {
    return formulation_ == Formulation::kInverseDynamics && mode_ == DerivativeMode::kAdjoint;
  }
  void stage_forward(int i);
  void batched_stage_dynamics(int stages);
  void stage_backward(int i, const VecX<double>& gmm_next, Eigen::Ref<VecX<double>> F_i);

  const Model& model_;
  Formulation formulation_;
  DerivativeMode mode_;
  OcpWeights weights_;
  VecX<double> q_ref_;
  int N_;
  bool timing_ = false;
  OcpTimes times_;

  std::vector<Data> stage_;  ///< one dynamics workspace per stage, kept between the sweeps
  bool batched_ = false;
  DataTpl<StagePack> pack_data_;                  ///< workspace of the batched stages
  VecX<StagePack> qp_, vp_, ap_, wp_;             ///< stage inputs packed in lanes
  MatX<double> gq_all_, gv_all_, Mw_all_;         ///< batched adjoints, n × N
  Data control_data_;        ///< for the applied torque
  MatX<double> q_, v_, a_, u_;  ///< n × (N+1) states, n × N inputs
  VecX<double> lmd_, gmm_, lmd_next_, gmm_next_;  ///< costates λ, γ (running)
  VecX<double> gq_, gv_, w_, qt_, vt_;            ///< stage scratch
};

}  // namespace idmpc
