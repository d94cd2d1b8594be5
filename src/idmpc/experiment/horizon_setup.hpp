#pragma once
/// @file horizon_setup.hpp
/// @brief What a task becomes on a given robot: the model both formulations' horizons use (the
/// plant's passive forces, formulations.md §Passive forces) and the weights the task leaves "auto". Everything chosen
/// here is chosen the same way for FD and ID, so that a comparison stays one of formulations,
/// and each automatic choice is stated in `notes`.
///
/// - Friction loss f (MuJoCo's dry-friction constraint) becomes the smooth torque f·tanh(v/ε).
///   "auto" ε_j = max(ε_min, Δτ·f_j·(M⁻¹)_jj): explicit in the friction, the horizon step's
///   velocity factor near v = 0 is (m − Δτ·f/ε)/(m + Δτ·d) ≥ 0 with m = 1/(M⁻¹)_jj, so the step
///   stays stable and without sign flips; its slope f/ε = m/Δτ is then of the order of MuJoCo's own
///   soft friction constraint (slope about m·2/timeconst, timeconst 0.02 s by default). ε_min
///   = 0.1 rad/s keeps the residual smooth enough for C/GMRES's continuation on light, stiff arms.
/// - Joint damping D is integrated implicitly over the horizon step Δτ = T_f/N
///   (with_implicit_damping) when asked, or with "auto" when the explicit Euler step would be
///   unstable or oscillating: Δτ·max eig(M⁻¹D) > 1 at q0 or q_ref.
/// - "auto" weights: Q_q = 100, Q_v = 10 (the shipped reach tasks'), and per joint
///   R_j = max(10/τ_j², Q_q/(m_j²·ω⁴)): τ_j the joint's torque range half-width (a full-range
///   torque costs as much as 0.32 rad of error; without a declared limit, the torque that holds
///   q_ref twice over plus 20 rad/s² of the joint's own inertia), and the second term keeps the
///   regulator of joint j alone (effective inertia m_j = 1/(M⁻¹)_jj at its lightest) no faster
///   than ω = 0.35/Δτ (17.5 rad/s at the default Δτ = 20 ms), well inside what the step resolves.
/// - The plant model (torque rule, observer) takes the damping implicitly over one plant step, as
///   MuJoCo's Euler and implicit integrators do.

#include <string>
#include <vector>

#include "idmpc/experiment/task.hpp"

namespace idmpc {

/// @brief The smallest smoothing velocity of "auto" friction [rad/s or m/s].
inline constexpr double kMinFrictionVelocity = 0.1;

struct HorizonSetup {
  /// the imported model with the plant's friction loss, smoothed, and its damping implicit over
  /// one plant step as MuJoCo's Euler and implicit integrators take it: the model of ID's torque
  /// rule (eqs. 27–28) and of the disturbance observer, which act over one plant step
  Model plant_model;
  Model horizon_model;  ///< plant_model, with its damping implicit where chosen
  OcpWeights weights;   ///< the task's, "auto" filled in
  bool implicit_damping = false;
  double damping_step_ratio = 0;   ///< Δτ·max eig(M⁻¹D) over q0 and q_ref
  VecX<double> friction_velocity;  ///< ε per joint (0 where there is no friction)
  std::vector<std::string> notes;  ///< what was chosen automatically, and why
};

/// @brief The horizon model and weights of `task` (resolved as `r`, with r.q0 filled in) on
/// `model` (the imported model, without friction), whose joints have MuJoCo's friction loss
/// `friction_loss` and the torque range [lower, upper] (±infinity where undeclared), simulated
/// with steps of `plant_step` seconds. Throws std::invalid_argument for sizes other than n.
HorizonSetup setup_horizon(const Task& task, const ResolvedTask& r, const Model& model,
                           const VecX<double>& friction_loss, const VecX<double>& lower,
                           const VecX<double>& upper, double plant_step);

}  // namespace idmpc
