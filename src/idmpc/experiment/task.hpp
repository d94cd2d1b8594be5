#pragma once
/// @file task.hpp
/// @brief Experiments are data: a task file (JSON) says which model to run, from where to where,
/// for how long, with which weights, C/GMRES settings, formulation and derivative mode. The
/// paper's swing-up is mjcf/paper_swingup.json and its tables mjcf/paper_tables.json; every
/// command, test, benchmark and script reads those files, so the paper's setup exists once.
///
/// Task file fields (all optional in a user's file: missing ones come from the defaults for real
/// arms, arm_defaults(), documented with their reasons in docs/tasks.md; the paper's swing-up names
/// every field itself; unknown fields, and a field given twice, are an error):
///   "model"        path of the MJCF/URDF file, relative to the task file's directory
///   "q0"           initial joint positions, one per joint, "swingup" = (−π, 0, …, 0) or
///                  "home" = the model's keyframe named home
///   "qref"         target joint positions: a scalar, one per joint, or "q0" (the start)
///   "duration"     simulated seconds
///   "formulation"  "fd" or "id";  "derivatives": "matrix" or "adjoint"
///   "simd_stages"  evaluate horizon stages in SIMD lanes where they are independent: ID (stage
///                  dynamics and products), FD matrix (stage derivatives after the rollout), FD
///                  adjoint under multiple shooting (bool)
///   "direct_torque" apply joint torques through qfrc_applied instead of the actuators (bool)
///   "actuate_every_joint" with direct_torque on an under-actuated model: the user's confirmation
///                  that every joint becomes actuated (bool)
///   "implicit_damping" integrate joint damping implicitly in the horizon (with_implicit_damping,
///                  step T_f/N; C/GMRES needs alpha = 0): true, false or "auto" (when the explicit
///                  Euler step would be unstable, Δτ·max eig(M⁻¹D) > 1)
///   "friction_velocity" ε of the smooth joint friction f·tanh(v/ε) in the horizon: a scalar or
///                  one per joint [rad/s or m/s], or "auto" (the smallest that keeps the
///                  explicit horizon step stable)
///   "offset_free"  estimate the joint torque the model misses (disturbance observer) and add it
///                  to the horizon model of both formulations (bool)
///   "observer_time_constant" the observer's filter time constant [s]
///   "reach_tolerance" the target counts as reached when max|q − q_ref| at the end is below it
///   "torque_limit" |τ_j| ≤ this: a scalar or one per joint (empty: the model's actuator ranges)
///   "weights"      {"Qq", "Qv", "Qa", "R"}: scalars, one per joint, or "auto" (scaled by the
///                  model's torque limits, see arm_weights); "Qa_fallback": the Q_a an ID run
///                  that diverges with Q_a = 0 is rerun with by `sweep` (0 = none)
///   "target"       a target for a frame of the robot (a MuJoCo site or body), beside the joint
///                  terms (Qq and qref then weigh the posture): {"frame": name, "position":
///                  [x, y, z] or "start" (the frame's position at q0), "orientation": [w, x, y, z]
///                  or "start", "weights": {"position": a scalar or 3 values [1/m²],
///                  "orientation": w_o or "auto"}} (cost.hpp: FrameTarget)
///   "reference"    a reference that moves (experiment/trajectory_io.hpp: "shape": "circle",
///                  "line", "waypoints" or "csv"): the frame target's position with a target,
///                  else qref (one value per joint); it starts at the target's start value
///   "tracking_tolerance" a frame target counts as reached when the position error [m] is
///                  below it: its RMS over the run with a reference, at the end without
///   "latency"      compute latency in the closed loop (formulations.md §Compute latency): "none" (the paper's timing, the
///                  default), "measured" (each update's wall time) or a compute time in ms (a
///                  number): the torque of an update reaches the plant ⌈t_compute/δt⌉ plant steps
///                  after its measurement (mj::ClosedLoopSettings::latency)
///   "solver"       "cgmres", "riccati" (Gauss–Newton SQP with a Riccati recursion:
///                  solver/riccati.hpp) or "auto" (the default: the Riccati recursion on a fully
///                  actuated model, C/GMRES on an under-actuated one; horizon_setup.hpp); the horizon
///                  (N, Tf) and dt are the "cgmres" object's for both
///   "riccati"      {"iterations" per update (1: real-time iteration), "tolerance",
///                  "init_iterations", "init_tolerance", "barrier", "line_search"}
///   "cgmres"       {"N", "kmax" (or "auto"), "Tf", "alpha", "dt", "zeta" (0 = 1/dt), "h",
///                  "init_full_horizon": solve the full-horizon problem at t = 0 before the loop
///                  (needs an open horizon, e.g. alpha = 0; see Cgmres::initialize),
///                  "shooting": "single" or "multiple" (formulations.md §Multiple shooting)}

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/experiment/latency.hpp"
#include "idmpc/ocp/problem.hpp"
#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/controller.hpp"
#include "idmpc/solver/riccati.hpp"

namespace idmpc {

inline constexpr const char* kTaskSchema = "idmpc-task/1";

/// @brief A task's frame target as written (resolved on the model by mj::TaskRun).
struct FrameTask {
  std::string frame;                     ///< site or body name
  std::vector<double> position;          ///< world [m]; empty: the frame's position at q0
  std::vector<double> orientation;       ///< unit quaternion (w, x, y, z); empty: at q0
  std::vector<double> position_weight = {1e4};  ///< 1 or 3 values [1/m²]
  /// @brief w_o; none: "auto", kAutoOrientationWeight where the arm can hold any orientation of the
  /// frame (its Jacobian has rank 6), else 0 (mj::TaskRun decides, and says so)
  std::optional<double> orientation_weight;
};
/// @brief The "auto" orientation weight of a frame target an arm can orient freely.
inline constexpr double kAutoOrientationWeight = 100;

struct Task {
  std::string source;  ///< the task file it was read from, for messages
  std::string description;
  std::string model;   ///< model path, resolved against the task file's directory
  std::string q0_rule;             ///< "swingup", "home" or "" (then q0 holds the values)
  std::vector<double> q0;
  std::vector<double> qref;
  bool qref_start = false;         ///< "qref": "q0": the start configuration
  std::optional<FrameTask> target;
  nlohmann::json reference;        ///< the "reference" object as written; null: none
  double tracking_tolerance = 5e-3;
  double duration = 0;
  std::string formulation, derivatives;
  bool simd_stages = true;
  bool direct_torque = false;
  bool actuate_every_joint = false;
  std::string implicit_damping = "off";      ///< "on", "off" or "auto"
  std::vector<double> friction_velocity;     ///< empty: "auto"
  bool offset_free = false;
  double observer_time_constant = 0;
  double reach_tolerance = 0;
  std::vector<double> torque_limit;  ///< empty: the model's actuator ranges
  std::vector<double> Qq, Qv, Qa, R; ///< empty: "auto" (Qq, Qv, R only)
  double Qa_fallback = 0;
  int N = 0, kmax = 0;  ///< kmax 0: "auto", kDefaultKmax (kUnderActuatedKmax on an under-actuated model)
  double Tf = 0, alpha = 0, dt = 0, zeta = 0, h = 0;
  bool init_full_horizon = false;
  std::string shooting;  ///< "single" or "multiple"
  std::string products;  ///< "difference" or "exact" (formulations.md §Exact products)
  std::string latency = "none";  ///< "none", "measured" or a compute time in ms (parse_latency)
  std::string solver = "auto";    ///< "cgmres", "riccati" or "auto" (mj::TaskRun records the one chosen)
  RiccatiSettings riccati;        ///< the Riccati solver's settings
};

/// @brief The paper's swing-up task file, mjcf/paper_swingup.json of the data directory
/// (data_dir.hpp; throws std::runtime_error saying how to set it when it is not found).
std::string paper_task_path();
/// @brief The paper's tables file, mjcf/paper_tables.json of the data directory.
std::string paper_tables_path();

/// @brief Reads a task file; fields it lacks come from `base` (the paper's task if null).
/// Throws std::invalid_argument naming the file and field for a bad file.
Task load_task(const std::string& path, const Task* base = nullptr);
/// @brief A task from JSON over `base`; `where` names the source in messages. Paths are kept
/// as written.
Task task_from_json(const nlohmann::json& j, const std::string& where, const Task& base);
/// @brief The paper's swing-up task (read once from paper_task_path()).
const Task& paper_task();
/// @brief The defaults for real arms, the base of every task file but the paper's (each field
/// and its reason in docs/tasks.md).
const Task& arm_defaults();

/// @brief C/GMRES's GMRES iterations per update where a task leaves kmax "auto": the paper's 10,
/// and 20 on an under-actuated model, whose ID stages carry the passive torques' multipliers
/// (docs/tasks.md; measured on the cart-pole, ID's closed loop needs at least 15).
inline constexpr int kDefaultKmax = 10;
inline constexpr int kUnderActuatedKmax = 20;

nlohmann::json to_json(const Task& task);

/// @brief The largest horizon (N) a task may ask for: the controller's (kMaxHorizonStages; kmax
/// is bounded where the GMRES basis is sized: Gmres::checked).
inline constexpr int kMaxHorizonSteps = kMaxHorizonStages;

/// @brief A task made concrete for a model with n joints: validated vectors and settings.
struct ResolvedTask {
  /// @brief The controller's settings as far as the task gives them: Q_q, Q_v, R and ε empty where
  /// the task says "auto" (the Controller chooses them, horizon_setup.hpp). mj::TaskRun fills in
  /// what needs the model: the torque range, friction loss, plant step, frame target, references
  /// and q_start.
  ControllerSettings controller;
  VecX<double> q0;                 ///< empty for "home": the model's keyframe
  VecX<double> torque_limit;       ///< size n, +infinity where the task sets none
  Latency latency;                 ///< compute latency in the closed loop (none by default)
  std::vector<std::string> warnings;  ///< settings accepted but without effect (e.g. Q_a in FD)
};
/// @brief Throws std::invalid_argument naming the field (a scalar or n values expected,
/// non-negative weights, finite values, valid C/GMRES settings, N within kMaxHorizonSteps).
ResolvedTask resolve(const Task& task, int n);

/// @brief Whether the task weights no acceleration (every Q_a is 0): the case the paper's
/// Q_a fallback is for.
bool without_Qa(const Task& task);

/// @brief What to try after a divergence of this task, as options to change: one line
/// starting "try ", e.g. implicit damping when it was off and the explicit horizon step is
/// unstable (damping_step_ratio = Δτ·max eig(M⁻¹D) > 1), a small Q_a for ID, the full-horizon
/// start, a larger R, a smaller ζ. Where FD's C/GMRES rollout is ill-conditioned, open_loop_rate
/// λ·T_f > kIllConditionedGrowth (horizon_setup.hpp), only what applies there: ID, the Riccati
/// solver, a horizon of 4/λ at the same step, multiple shooting.
std::string divergence_hint(const Task& task, double damping_step_ratio = 0, double open_loop_rate = 0);

/// @brief One cell of the paper's Tables 1–3 (mjcf/paper_tables.json).
struct PaperCell {
  std::string table;  ///< "12" (arm4, N × kmax) or "3" (n-link chains)
  std::string model;  ///< file name beside the tables file
  int n = 0;
  std::string formulation;
  int N = 0, kmax = 0;
  double ms = 0;      ///< the paper's mean ms per update
  std::string mark;   ///< "*" FD diverged, "†" ID needed Q_a = 1e-4, or ""
};
struct PaperTables {
  std::string source, machine;
  std::string task;   ///< the task every cell runs (path resolved)
  std::vector<PaperCell> cells;
  /// @brief The paper's figure for a cell, or nullptr.
  const PaperCell* find(const std::string& table, const std::string& formulation, int n, int N,
                        int kmax) const;
};
PaperTables load_paper_tables(const std::string& path = paper_tables_path());

}  // namespace idmpc
