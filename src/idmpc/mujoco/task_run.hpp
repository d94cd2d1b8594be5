#pragma once
/// @file task_run.hpp
/// @brief A task on its MuJoCo model, ready to run: the one place where a task file becomes a
/// plant and a controller. The command line, the tests, the benchmarks, the Python module and
/// users' own loops build their runs here.
///
///     idmpc::mj::TaskRun run(idmpc::load_task("my_reach.json"));
///     idmpc::Controller& c = run.controller();   // or run.run() for the whole closed loop
///     c.initialize(q, v);                         // torque for the first period: c.torque()
///     c.update(t, q, v);                          // every Δt = c.dt(); false: diverged
///
/// What the run does with the model (translations of newer MJCF, servos replaced by torques,
/// the horizon's passive forces and automatic weights, limits) is said in notices(); settings
/// accepted without effect and risks in warnings(). Both are ready before anything runs.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "idmpc/experiment/run_record.hpp"
#include "idmpc/mujoco/closed_loop.hpp"
#include "idmpc/mujoco/hold.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/solver/controller.hpp"

namespace idmpc::mj {

class TaskRun {
 public:
  /// @brief Loads the task's model (MJCF of MuJoCo 2.2 or newer, URDF), imports it, resolves
  /// the task on it and builds the plant and the controller. Throws std::invalid_argument (bad
  /// task values, unsupported model features) or std::runtime_error (unreadable files), with a
  /// one-line message naming the file, field or joint.
  explicit TaskRun(const Task& task);
  TaskRun(const TaskRun&) = delete;
  TaskRun& operator=(const TaskRun&) = delete;

  const Task& task() const { return task_; }
  /// @brief The task made concrete on the model (q0 filled in from the keyframe if asked).
  const ResolvedTask& resolved() const { return resolved_; }
  /// @brief The controller's MuJoCo model: the task's, with the held joints welded if it has
  /// any (hold.hpp); its dofs are the controller's.
  const mjModel* mj_model() const { return models_.model(); }
  /// @brief The plant's MuJoCo model: the task's, as loaded.
  const mjModel* plant_model() const { return models_.full.model.get(); }
  /// @brief The joints the controller holds (none for most arms).
  const HeldJoints& held() const { return models_.held; }
  /// @brief The imported rigid-body model (no friction; the plant's joints).
  const Model& model() const { return *model_; }
  std::shared_ptr<const Model> shared_model() const { return model_; }
  const ImportedModel& imported() const { return imported_; }
  /// @brief The controller's settings: the task's, with the model's torque range, friction loss,
  /// plant step, frame target and references filled in. A Controller built from them and
  /// shared_model() is the one this run drives (its "auto" choices made the same way).
  const ControllerSettings& settings() const { return resolved_.controller; }
  /// @brief The horizon's model, weights and automatic choices (HorizonSetup), as the controller
  /// made them.
  const HorizonSetup& horizon() const { return *controller_->horizon_setup(); }
  Controller& controller() { return *controller_; }
  const Controller& controller() const { return *controller_; }
  /// @brief The MuJoCo plant, its control period set to the controller's Δt.
  Plant& plant() { return *plant_; }
  int n() const { return model_->n; }
  const VecX<double>& q0() const { return resolved_.q0; }
  /// @brief The actuators' range narrowed by the task's torque_limit (±infinity: unbounded):
  /// the horizon's constraints and the clamp of every torque the plant receives.
  const VecX<double>& torque_lower() const { return lower_; }
  const VecX<double>& torque_upper() const { return upper_; }
  /// @brief Joints without a torque bound on either side, by name.
  const std::vector<std::string>& unbounded_joints() const { return unbounded_; }
  const std::vector<std::string>& notices() const { return notices_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

  /// @brief The closed loop of the task: from (q0, 0) for task().duration, on_step called for
  /// every control step. A divergence is recorded in the result, never thrown.
  RunResult run(const std::function<void(const StepRecord&)>& on_step = {});
  /// @brief The same with other loop settings (start, duration, timing; loop_settings() gives
  /// the task's).
  RunResult run(const ClosedLoopSettings& settings, const std::function<void(const StepRecord&)>& on_step = {});
  ClosedLoopSettings loop_settings() const;

  /// @brief The run's summary (the JSON of `swingup --summary`): the task, what was chosen,
  /// timings and outcome. `log_path`: the run's CSV log, hashed for `render` (empty: none).
  RunSummary summary(const RunResult& result, const std::string& log_path = "") const;
  /// @brief The warning for a C/GMRES full-horizon start left unsolved, ‖F‖ = init_residual above
  /// kStartSolved (empty otherwise, and for the Riccati solver, whose start is its own): said when
  /// the loop starts and kept in the summary's warnings.
  std::string start_warning(double init_residual) const;

 /// @brief The frame target of the task (none without "target") and its moving reference, or
  /// the moving joint reference (null: none).
  const std::optional<FrameTarget>& frame_target() const { return frame_target_; }
  const std::shared_ptr<const Trajectory>& reference() const { return reference_; }

 private:
  // the task's frame target, reference and what the tracking error is measured against
  void set_up_references();

  Task task_;
  ControllerModel models_;
  ImportedModel imported_;
  std::shared_ptr<const Model> model_;
  ResolvedTask resolved_;
  VecX<double> lower_, upper_;
  std::unique_ptr<Plant> plant_;
  std::unique_ptr<Controller> controller_;
  std::vector<std::string> unbounded_, notices_, warnings_;
  std::vector<std::string> auto_notes_;  ///< the automatic choices made while resolving the task
  std::optional<FrameTarget> frame_target_;
  std::shared_ptr<const Trajectory> reference_;
  TrackingSettings tracking_;
};

/// @brief MuJoCo's friction loss per dof (zero where the model disables it).
VecX<double> friction_loss(const mjModel* m);

}  // namespace idmpc::mj
