#pragma once
/// @file closed_loop.hpp
/// @brief Simulation in the loop: every Δt the controller reads (q, v) from the MuJoCo plant,
/// runs one C/GMRES update and applies its torque for one plant step (formulations.md §The torque rule), or, with
/// compute latency, as soon as its computation ends (formulations.md §Compute latency).

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "idmpc/experiment/latency.hpp"
#include "idmpc/experiment/run_record.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/solver/controller.hpp"

namespace idmpc::mj {

/// @brief Update times a run keeps by default (8 MiB; 17 min of control at 1 kHz).
inline constexpr long kKeptUpdateTimes = 1L << 20;
/// @brief Control steps a run may have at most (11.6 days at 1 kHz).
inline constexpr double kMaxSteps = 1e9;

/// @brief What a run's tracking error is measured against, on the plant: a frame (a MuJoCo site or
/// body, by MuJoCo's kinematics of the measured q) and its target at each step's time, and a
/// moving joint target.
struct TrackingSettings {
  int site = -1;                 ///< the frame as a site of the plant's model, or
  int body = -1;                 ///< as a body (when site < 0); both < 0: no frame
  std::shared_ptr<const Trajectory> position;   ///< p_ref(t); null: `fixed_position`
  Vec3<double> fixed_position = Vec3<double>::Zero();
  Mat3<double> rotation = Mat3<double>::Identity();  ///< R_ref
  std::shared_ptr<const Trajectory> joints;     ///< q_ref(t); null: the controller's fixed target
  bool frame() const { return site >= 0 || body >= 0; }
};

struct ClosedLoopSettings {
  double duration = 10.0;
  VecX<double> q0, v0;
  bool phase_timing = true;  ///< split each update's time into rollout/costate/GMRES
  long kept_update_times = kKeptUpdateTimes;  ///< RunResult::update_ms keeps at most this many
  TrackingSettings tracking;  ///< what the tracking error is measured against (none by default)
  /// @brief Compute latency (formulations.md §Compute latency). none: the paper's timing, every update's torque applied
  /// over the period after its measurement. On: the torque computed from the state measured at t
  /// reaches the plant at t + ⌈t_compute/δt⌉·δt (δt the plant's MuJoCo step; t_compute the
  /// update's wall time, or the fixed figure) and is held until the next one arrives; the
  /// controller starts an update only at a control step when it is not busy with the previous
  /// one, and aims its torque at the actual delay (Controller::aim). Until the first update's
  /// torque arrives the plant holds the initialization's torque.
  Latency latency;
};

/// @brief One control step as logged: measured state, the torque the plant applied over
/// [t, t + Δt) and the one the controller commanded (they differ where it saturated),
/// residual and update time.
struct StepRecord {
  double t;
  const VecX<double>& q;
  const VecX<double>& v;
  const VecX<double>& u;
  const VecX<double>& u_commanded;
  double residual;
  double update_ms;  ///< NaN at a step where no update started (the controller still busy, latency on)
  /// @brief With a frame target (TrackingSettings): the frame's measured position and its target
  /// at t; null otherwise.
  const Vec3<double>* frame_position = nullptr;
  const Vec3<double>* frame_target = nullptr;
};

struct RunResult {
  bool diverged = false;
  double diverged_at = std::numeric_limits<double>::quiet_NaN();
  std::string divergence_reason;
  int steps = 0;                    ///< control steps completed (rows logged)
  /// @brief Times of the successful updates [ms] (each includes the torque to apply): all of
  /// them up to ClosedLoopSettings::kept_update_times, beyond that a uniform random sample of that size, so that
  /// memory does not grow with the duration (percentiles are then estimates)
  std::vector<double> update_ms;
  long updates = 0;                 ///< successful updates
  double mean_update_ms = 0;        ///< over all of them (exact)
  double max_update_ms = 0;         ///< over all of them (exact)
  /// @brief Updates whose compute time (measured, or the fixed latency) exceeded the control
  /// period Δt: deadline misses at the control rate, counted with latency on or off.
  long deadline_misses = 0;
  /// @brief RMS over the control steps of ‖q − q_ref(t)‖ [rad or m]: the run's tracking cost.
  double joint_error_rms = 0;
  double init_residual = 0;         ///< ‖F_0‖ after the zero-horizon Newton solve
  double mean_residual = 0;
  /// @brief ∫ L dt of the task's stage cost along the measured trajectory and the applied
  /// torques, Σ L(q_k, v_k, τ_k; t_k)·Δt over the steps before a divergence, each at the references of its own
  /// time t_k (StageTerms::stage_cost_at; d̂ the controller's estimate then)
  double closed_loop_cost = 0;
  int evaluations_per_update = 0;   ///< F evaluations in one update
  UpdateTimes mean_phase_ms;        ///< mean of each phase [ms]
  VecX<double> final_q, final_v;
  std::vector<std::string> warnings;  ///< e.g. the model's timestep replaced
  std::vector<long> saturated_steps;  ///< per joint: steps whose applied torque was clamped
  long saturated_any = 0;           ///< steps with at least one clamped joint
  /// @brief Largest Controller::constraint_violation over the updates [N m]: how far the OCP's
  /// own solution left the torque bounds (the plant's torques are clamped regardless).
  double max_constraint_violation = 0;
  long contact_steps = 0;         ///< control steps with a contact in the plant (Plant::contact_steps)
  double max_contact_force = 0;   ///< the largest contact normal force [N]
  VecX<double> final_disturbance;  ///< the controller's estimate d̂ at the end (zero without observer)
  /// @brief With a frame target: the tracking error (TrackingSettings).
  std::optional<TrackingResult> tracking;
  /// @brief max |q_i − q_ref,i| at the end (q_ref at the end's time for a moving target); after a divergence, of the last measured state
  /// (before MuJoCo's reset of a blown-up simulation)
  double final_q_error = 0;
  double final_v_norm = 0;
};

/// @brief Runs the closed loop from (q0, v0) for `duration` (the plant's control period set to
/// the controller's Δt beforehand, Plant::set_control_period), calling on_step for each logged
/// step: plant I/O only, the controller owns the timing of its torques (eqs. 27–28). A
/// divergence, or a MuJoCo error in the plant (its handler throws std::runtime_error, load.hpp),
/// ends the run cleanly: it is recorded in the result (diverged, with MuJoCo's message as the
/// reason), never thrown. Throws std::invalid_argument for bad settings (sizes, duration), and
/// lets through what on_step throws.
RunResult run_closed_loop(Plant& plant, Controller& controller, const ClosedLoopSettings& settings,
                          const std::function<void(const StepRecord&)>& on_step);

/// @brief Median-style percentile (p in [0, 100]) of a sample, NaN when empty.
double percentile(std::vector<double> x, double p);

}  // namespace idmpc::mj
