#pragma once
/// @file horizon_setup.hpp
/// @brief What a Controller's settings become on its model: the model both formulations' horizons
/// use (the plant's passive forces, formulations.md §Passive forces) and the weights the settings
/// leave "auto". Everything chosen here is chosen the same way for FD and ID, so that a comparison
/// stays one of formulations, and each automatic choice is stated in `notes`. The Controller makes
/// these choices (Controller::horizon_setup), whoever built its settings.
///
/// - Friction loss f (MuJoCo's dry-friction constraint) becomes the smooth torque f·tanh(v/ε).
///   "auto" ε_j = max(ε_min, Δτ·f_j·(M⁻¹)_jj): explicit in the friction, the horizon step's
///   velocity factor near v = 0 is (m − Δτ·f/ε)/(m + Δτ·d) ≥ 0 with m = 1/(M⁻¹)_jj, so the step
///   stays stable and without sign flips; its slope f/ε = m/Δτ is then of the order of MuJoCo's own
///   soft friction constraint (slope about m·2/timeconst, timeconst 0.02 s by default). ε_min
///   = 0.1 rad/s keeps the residual smooth enough for C/GMRES's continuation on light, stiff arms.
/// - Joint damping D is integrated implicitly over the horizon step Δτ = T_f/N
///   (with_implicit_damping) when asked, or with "auto" when the explicit Euler step would be
///   unstable or oscillating: Δτ·max eig(M⁻¹D) > 1 at q_start or q_ref.
/// - "auto" weights: Q_q = 100, Q_v = 10 (the shipped reach tasks'; with a frame target 1 and 1:
///   the joint terms then only hold the posture), and per joint
///   R_j = max(10/τ_j², Q_q/(m_j²·ω⁴)): τ_j the joint's torque range half-width (a full-range
///   torque costs as much as 0.32 rad of error; without a declared limit, the torque that holds
///   q_ref twice over plus 20 rad/s² of the joint's own inertia), and the second term keeps the
///   regulator of joint j alone (effective inertia m_j = 1/(M⁻¹)_jj at its lightest) no faster
///   than ω = 0.35/Δτ (17.5 rad/s at the default Δτ = 20 ms), well inside what the step resolves.
/// - The open loop's rate λ: the largest real part of the eigenvalues of the horizon model's
///   dynamics linearized at rest (torques held) at q_start and q_ref,
///   [[0, I], [−M⁻¹∂τ/∂q, −M⁻¹∂τ/∂v]] (gravity, springs, damping and the friction's slope), 0 where
///   it is stable. FD's single-shooting rollout amplifies an early torque's effect by up to e^{λT_f}
///   over the horizon; above e^{kIllConditionedGrowth} C/GMRES in FD is ill-conditioned there and
///   mostly diverges on such arms, where ID's rollout (accelerations integrated) is not: said at
///   start, and named in the divergence hint with what applies.
/// - Solver "auto": the Riccati recursion on a fully actuated model, C/GMRES on an under-actuated
///   one; decided on the model, never on the formulation, so that FD and ID are compared under one
///   solver. Where C/GMRES holds, the Riccati recursion reaches as well, at a fraction of the cost
///   per update; where it does not, FD's C/GMRES diverges in ways no quantity of the model we tried
///   predicts (above the open-loop line mostly, below it too: light joints, where a continuation
///   step of 10 GMRES iterations cannot follow how fast F moves with the state). On four generated
///   reach sets of 36 arms and one of circles the Riccati recursion reached every arm C/GMRES
///   reached, in both formulations (results.md, "The default solver"). Under-actuated models keep
///   C/GMRES: their target is unstable by construction (the passive joints'), and C/GMRES swings
///   the cart-pole up in both formulations.
/// - The plant model (torque rule, observer) takes the damping implicitly over one plant step, as
///   MuJoCo's Euler and implicit integrators do.
/// - An under-actuated model's terminal cost is the LQR value ½eᵀP e of its fixed joint target
///   (formulations.md §Under-actuation): P solves the discrete algebraic Riccati equation of the
///   horizon's explicit Euler step Δτ = T_f/N linearized at (q_ref, 0) with the actuators' holding
///   torque, stage weights Δτ·diag(Q_q, Q_v) and Δτ·R on the actuated joints, so that the horizon
///   ends on the cost of the infinite horizon near the target and a short horizon still stabilizes
///   the passive joints. Not with a growing horizon (C/GMRES with alpha > 0: its step is not P's,
///   and a swing-up starts far from where the LQR value means anything), where the target needs a
///   torque on a passive joint (not an equilibrium), with a frame target, or where the equation
///   has no stabilizing solution: then the diagonal terminal weights, with a note.

#include <memory>
#include <string>
#include <vector>

#include "idmpc/model/model.hpp"
#include "idmpc/spatial/spatial.hpp"
#include "idmpc/solver/controller_settings.hpp"

namespace idmpc {

/// @brief λT_f above which FD's single-shooting rollout is ill-conditioned for C/GMRES (an
/// amplification e^4.5 ≈ 90 over the horizon), said at start where FD runs under C/GMRES: on
/// generated arms FD's C/GMRES diverges on most arms above it and on few below (results.md,
/// "Generated arms with the defaults").
inline constexpr double kIllConditionedGrowth = 4.5;

/// @brief The smallest smoothing velocity of "auto" friction [rad/s or m/s].
inline constexpr double kMinFrictionVelocity = 0.1;

struct HorizonSetup {
  /// the model with the plant's friction loss, smoothed, and its damping implicit over one plant
  /// step as MuJoCo's Euler and implicit integrators take it: the model of ID's torque rule
  /// (eqs. 27–28) and of the disturbance observer, which act over one plant step
  std::shared_ptr<const Model> plant_model;
  std::shared_ptr<const Model> horizon_model;  ///< plant_model, with its damping implicit where chosen
  OcpWeights weights;   ///< the settings', "auto" filled in (Q_a empty: zero)
  SolverKind solver = SolverKind::kCgmres;  ///< the settings', "auto" resolved (never kAuto)
  bool implicit_damping = false;
  double damping_step_ratio = 0;   ///< Δτ·max eig(M⁻¹D) over q_start and q_ref
  double open_loop_rate = 0;       ///< λ [1/s]: the fastest growth of the open loop at q_start and q_ref (0: stable)
  VecX<double> friction_velocity;  ///< ε per joint (0 where there is no friction)
  std::vector<std::string> notes;  ///< what was chosen automatically, and why
  MatX<double> terminal_weight;    ///< under-actuated: the LQR value's P (2n × 2n), else empty
};

/// @brief P of the discrete algebraic Riccati equation P = Q + AᵀPA − AᵀPB(R + BᵀPB)⁻¹BᵀPA
/// (Q, R symmetric, R positive definite), by the structured doubling algorithm; empty if it does
/// not converge to a finite stabilizing solution.
MatX<double> solve_dare(const MatX<double>& A, const MatX<double>& B, const MatX<double>& Q, const MatX<double>& R);

/// @brief The horizon model and weights of `settings` on `model` (the rigid-body model, without
/// the plant's friction loss, which settings.friction_loss gives). Throws std::invalid_argument
/// naming the setting for vectors of a size other than n (or empty where "auto" or "none" is
/// allowed).
HorizonSetup setup_horizon(const Model& model, const ControllerSettings& settings);

}  // namespace idmpc
