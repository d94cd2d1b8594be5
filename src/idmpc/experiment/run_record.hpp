#pragma once
/// @file run_record.hpp
/// @brief The record of one closed-loop run, with one writer and one reader for each part
/// (schema in docs/run_record.md):
///   - the per-step log (CSV): `t,q0..q{n-1},v0..v{n-1},u0..u{n-1}[,uc0..uc{n-1}],residual,
///     update_ms[,x,y,z,x_ref,y_ref,z_ref]`, one row per control step: measured state, torque
///     applied over [t, t + Δt), the torque commanded before clamping to the actuator limits (only
///     for runs with limits), ‖F‖ at the start of the update, the update's wall time, and for runs
///     with a frame target the frame's measured world position and its target at t;
///   - the summary (JSON): schema version, the task as run, outcome and timing.

#include <cstddef>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/experiment/task.hpp"

namespace idmpc {

inline constexpr int kRunRecordSchema = 1;

/// @brief Writes the per-step log: header at construction, then one row per call.
class RunLogWriter {
 public:
  /// @param commanded whether the log has the commanded-torque columns uc*
  /// @param frame whether it has a frame's position and target (x, y, z, x_ref, y_ref, z_ref)
  RunLogWriter(std::ostream& out, int n, bool commanded, bool frame = false);
  /// @brief One row; frame_position and frame_target (with `frame`; null: NaN) in world coordinates.
  void row(double t, const VecX<double>& q, const VecX<double>& v, const VecX<double>& u,
           const VecX<double>& u_commanded, double residual, double update_ms,
           const Vec3<double>* frame_position = nullptr, const Vec3<double>* frame_target = nullptr);

 private:
  std::ostream& out_;
  int n_;
  bool commanded_, frame_;
};

/// @brief The tracking error of a run with a frame target, over its control steps (measured on
/// the plant).
struct TrackingResult {
  double position_rms = 0, position_max = 0;        ///< |p − p_ref| [m]
  double orientation_rms = 0, orientation_max = 0;  ///< angle of R_refᵀR [rad]
  double final_position_error = 0;                  ///< at the last measured state [m]
  long samples = 0;
};

/// @brief Outcome and timing of a run (the JSON summary), with the task it ran.
struct RunSummary {
  int schema = kRunRecordSchema;
  Task task;                ///< settings as run (model path, weights, solver, formulation…)
  int n = 0;
  bool simd_stages = false;  ///< whether stages actually ran in SIMD lanes
  double zeta = 0;           ///< ζ actually used (1/Δt when the task says 0)
  int steps = 0;
  bool diverged = false;
  double diverged_at = std::numeric_limits<double>::quiet_NaN();
  std::string divergence_reason;
  std::string divergence_hint;  ///< what to try (divergence_hint(task)), empty unless diverged
  double mean_update_ms = 0, p50_update_ms = 0, p95_update_ms = 0, max_update_ms = 0;
  /// @brief The compute latency the run had ("none", "measured" or ms; task.latency) and the
  /// updates whose compute time exceeded the control period (deadline misses; counted with any
  /// setting, "latency" in the JSON)
  long updates = 0, deadline_misses = 0;
  double control_period_ms = 0;
  /// @brief RMS over the control steps of ‖q − q_ref(t)‖: the run's tracking cost
  double joint_error_rms = 0;
  double rollout_ms = 0, costate_ms = 0, gmres_ms = 0;  ///< mean per update
  int evaluations_per_update = 0;
  double init_residual = 0, final_q_error = 0, final_v_norm = 0, mean_residual = 0;
  /// @brief ∫ L dt of the task's stage cost along the run (NaN in summaries written without it)
  double closed_loop_cost = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> torque_lower, torque_upper;  ///< limits the plant's torques were held to
  std::vector<long> saturated_steps;               ///< per joint: steps clamped to a limit
  long saturated_any = 0;                          ///< steps with any joint clamped
  /// @brief Largest excess of the OCP solution's stage torques over their bounds [N m]
  double max_constraint_violation = 0;
  /// @brief Whether the target was reached: max|q − q_ref| at the end below task.reach_tolerance,
  /// without divergence
  bool reached = false;
  /// @brief With a frame target: its tracking error ("tracking" in the JSON; absent otherwise).
  std::optional<TrackingResult> tracking;
  long contact_steps = 0;          ///< control steps with a contact in the plant
  double max_contact_force = 0;    ///< the largest contact normal force [N]
  std::vector<double> final_disturbance;  ///< the observer's d̂ at the end (offset-free tracking)
  bool implicit_damping = false;   ///< whether the horizon integrated damping implicitly
  double open_loop_rate = 0;       ///< λ [1/s]: the fastest growth of the open loop at q0 and q_ref (horizon_setup.hpp)
  std::vector<double> friction_velocity;  ///< ε of the horizon's smooth friction (0: none)
  std::vector<double> Qq, Qv, R;   ///< the weights as run ("auto" resolved)
  std::vector<std::string> unbounded_joints;  ///< joints without a declared torque limit
  /// @brief The controller's joints, in the log's column order, and their kinds ("hinge": q in
  /// rad, u in N m; "slide": m and N)
  std::vector<std::string> joint_names, joint_types;
  /// @brief Joints the controller held (a gripper's fingers, hold.hpp), not in the log's q,
  /// and where it held them
  std::vector<std::string> held_joints;
  std::vector<double> held_q;
  std::vector<std::string> unmodeled;
  /// @brief said at the start: what loading translated or replaced, what was chosen automatically
  std::vector<std::string> notices;
  std::vector<std::string> warnings;  ///< said at the start: unmodeled features, ranges, timestep
  /// @brief file_hash() of the model file as run, and of the log as written ("" in summaries
  /// written before these fields existed, and for a log that is no regular file)
  std::string model_hash, log_hash;

  /// @brief "C/GMRES (ID, adjoint) N=25 kmax=10"
  std::string label() const;
};

/// @brief A stable hash of a regular file's bytes: "fnv1a64:" and 16 hex digits (FNV-1a, 64 bit);
/// "" for an empty path or a path that is no regular file (a device, a FIFO).
/// @throws std::runtime_error naming the file if it cannot be read
std::string file_hash(const std::string& path);
/// @brief The same hash of a string (e.g. a task as JSON), "fnv1a64:<16 hex digits>".
std::string text_hash(const std::string& text);

nlohmann::json to_json(const RunSummary& s);
/// @brief Throws std::runtime_error naming `source` for a summary of another schema version or
/// with a missing or mistyped field.
RunSummary summary_from_json(const nlohmann::json& j, const std::string& source);
/// @brief Reads a summary file.
RunSummary read_summary(const std::string& path);

/// @brief One closed-loop run: per control step the time, the plant's q, the applied torque u,
/// the optimality residual and the controller's update time.
///
/// CSV header: `t,q0..q{n-1},v0..v{n-1},u0..u{n-1},residual,update_ms`; v is checked but not
/// kept. Values may be nan/inf (a diverged run); the renderer holds the last finite pose.
struct RunLog {
  std::string path;   ///< the CSV file it was read from
  std::string label;  ///< e.g. "C/GMRES (ID, adjoint) N=25 kmax=10", or the file's stem
  std::string formulation;  ///< "fd" / "id" from the JSON summary, or ""
  std::string derivatives;  ///< "matrix" / "adjoint" / ... from the JSON summary, or ""
  int n = 0;          ///< joints (columns q0..q{n-1})
  int nu = 0;         ///< torque columns u0..u{nu-1} (n for the fully actuated arms)
  std::vector<double> t;          ///< rows
  std::vector<double> q;          ///< rows x n, row-major
  std::vector<double> u;          ///< rows x nu, row-major
  std::vector<double> u_commanded;  ///< rows x nu, row-major, if the log has uc* columns
  std::vector<double> residual;   ///< rows
  std::vector<double> update_ms;  ///< rows
  /// @brief With a frame target: its measured world position and its target, rows × 3 each,
  /// row-major (empty otherwise)
  std::vector<double> frame, frame_ref;
  /// @brief From the sibling summary when it was used: its path, the model it names (as run)
  /// and that model file's hash ("" if the summary has none); all "" otherwise
  std::string summary_path, summary_model, model_hash;
  /// @brief From the sibling summary: the joints the controller held, not in q, and where
  std::vector<std::string> held_joints;
  std::vector<double> held_q;
  /// @brief Why a sibling summary was not used (unreadable, or of another run), or ""
  std::string summary_warning;

  std::size_t rows() const { return t.size(); }
  const double* q_row(std::size_t i) const { return q.data() + i * static_cast<std::size_t>(n); }
  const double* u_row(std::size_t i) const { return u.data() + i * static_cast<std::size_t>(nu); }
  /// @brief Euclidean norm of u in row i.
  double u_norm(std::size_t i) const;
  /// @brief Index of the row whose time is nearest to `time` (rows() must be > 0).
  std::size_t nearest_row(double time) const;
  /// @brief Whether q of row i is finite.
  bool finite_pose(std::size_t i) const;
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front(); }
};

/// @brief Reads a run log CSV and, when `<same path>.json` exists beside it, its summary for
/// the label and the model. A sibling summary that cannot be read, or that belongs to another
/// run (another joint count or number of steps, or a log hash that is not this log's), is not
/// used: the label is the file's stem and summary_warning says why. Throws std::runtime_error
/// naming the file (and the line number) for a missing or unreadable file, a bad header, a row
/// with the wrong number of columns, a non-numeric value, non-increasing times or no rows.
RunLog read_run_log(const std::string& csv_path);

}  // namespace idmpc
