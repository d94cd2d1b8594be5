#pragma once
/// @file controller_settings.hpp
/// @brief The one settings type of a controller: what the command line, a task file, C++ and
/// Python all build a Controller from. The choices a task leaves "auto" (weights, the friction's
/// smoothing, implicit damping) are settings too, made by the Controller from its model by the
/// rules of horizon_setup.hpp, so that a controller built by hand from these settings is the one
/// the command line runs (mj::TaskRun::settings() gives a task's).

#include <memory>
#include <optional>
#include <string>

#include "idmpc/ocp/cost.hpp"
#include "idmpc/ocp/problem.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/mpc_solver.hpp"
#include "idmpc/solver/riccati.hpp"

namespace idmpc {

/// @brief Joint damping over the horizon step: explicit, implicit (Model::with_implicit_damping,
/// step T_f/N; needs a fixed horizon), or implicit where the explicit step would be unstable,
/// Δτ·max eig(M⁻¹D) > 1 (horizon_setup.hpp).
enum class ImplicitDamping { kOff, kOn, kAuto };
/// @brief "off"/"on"/"auto"; parse throws std::invalid_argument naming the value.
std::string to_string(ImplicitDamping d);
ImplicitDamping parse_implicit_damping(const std::string& s);

/// @brief Everything a controller is built from, besides its model. Vectors have one entry per
/// joint; Controller's constructor checks them and names the first bad one.
struct ControllerSettings {
  Formulation formulation = Formulation::kInverseDynamics;
  DerivativeMode derivatives = DerivativeMode::kAdjoint;
  int N = 25;                 ///< horizon stages
  /// @brief The solver family (mpc_solver.hpp): C/GMRES (the default here), the Riccati
  /// recursion, or kAuto, resolved by the horizon setup (horizon_setup.hpp;
  /// Controller::solver_kind() says which).
  SolverKind solver = SolverKind::kCgmres;
  /// @brief The sampling period Δt and the horizon T_f (both solvers); α, kmax, ζ, h, shooting
  /// scheme, products and start (C/GMRES).
  CgmresSettings cgmres;
  RiccatiSettings riccati;    ///< iterations per update, tolerances, barrier (Riccati)
  /// @brief Q_q, Q_v, Q_a, R. Q_q, Q_v or R empty: "auto" (horizon_setup.hpp); Q_a empty: zero.
  OcpWeights weights;
  VecX<double> q_ref;         ///< the joint target; Controller::set_target changes it between updates
  /// @brief The configuration the run starts from, which the automatic choices consider beside
  /// q_ref (the inertia and damping they scale with); empty: q_ref alone.
  VecX<double> q_start;
  /// @brief A moving joint target q_ref(t) (its rate the velocity reference); null: q_ref.
  std::shared_ptr<const Trajectory> joint_reference;
  /// @brief A target for a frame of the robot (cost.hpp: position and orientation weights),
  /// beside the joint terms (with a frame target, Q_q and q_ref weigh the posture).
  std::optional<FrameTarget> frame_target;
  /// @brief The frame target's position moving as p_ref(t); null: FrameTarget::position.
  std::shared_ptr<const Trajectory> frame_reference;
  /// @brief The actuators' torque range, given once: the horizon's constraints (formulations.md §Torque limits) on
  /// every joint bounded on both sides, and the clamp of every torque the controller returns.
  /// Empty: unbounded; ±infinity per joint: that joint unbounded.
  VecX<double> torque_lower, torque_upper;
  /// @brief false: the limits only clamp the returned torque; the horizon is unconstrained.
  bool limits_in_horizon = true;
  double observer_time_constant = 0;  ///< disturbance observer (formulations.md §Disturbance observer); 0: off
  bool simd_stages = true;            ///< stages in SIMD lanes where independent

  // The plant's passive forces the model lacks, as the horizon and the torque rule take them
  // (formulations.md §Passive forces).
  /// @brief The plant's dry friction per joint [N m or N] (MuJoCo's frictionloss, mj::friction_loss):
  /// the horizon and the torque rule model it as f·tanh(v/ε). Empty: the model's own friction terms.
  VecX<double> friction_loss;
  /// @brief ε of the smooth friction per joint [rad/s or m/s]; empty: "auto" (horizon_setup.hpp).
  VecX<double> friction_velocity;
  ImplicitDamping implicit_damping = ImplicitDamping::kOff;
  /// @brief The plant's integration step [s]: the model of the torque rule and of the observer takes
  /// the joint damping implicitly over it, as MuJoCo's Euler and implicit integrators do; 0: explicit.
  double plant_step = 0;
};

/// @brief The largest horizon (N) a controller takes: far above any useful setting (the paper's
/// largest is 50), and small enough that the stage workspace, sized from it, fits in memory.
inline constexpr int kMaxHorizonStages = 10000;

/// @brief Throws std::invalid_argument naming the setting unless the settings' scalars can size a
/// controller: N from 1 to kMaxHorizonStages, a finite non-negative plant step. Controller's
/// constructor calls it first.
void validate(const ControllerSettings& settings);

}  // namespace idmpc
