#include "idmpc/mujoco/task_run.hpp"

#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/experiment/trajectory_io.hpp"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>

namespace idmpc::mj {

VecX<double> friction_loss(const mjModel* m) {
  VecX<double> f = VecX<double>::Zero(m->nv);
  if (m->opt.disableflags & (mjDSBL_FRICTIONLOSS | mjDSBL_CONSTRAINT)) return f;
  for (int i = 0; i < m->nv; ++i) f[i] = m->dof_frictionloss[i];
  return f;
}

namespace {

ImportOptions import_options(const Task& task, const LoadedModel& loaded) {
  ImportOptions o;
  o.direct_torque = task.direct_torque;
  o.actuate_every_joint = task.actuate_every_joint;
  o.joint_force_lower = loaded.joint_force_lower;
  o.joint_force_upper = loaded.joint_force_upper;
  return o;
}

// a frame's 6×n Jacobian at q and at q + 0.1 rad·(1, −1, 1, …), side by side (6×2n): where a
// start at a singular pose does not decide what the arm can do
MatX<double> jacobians_at_and_beside(const Model& model, const Frame& frame, const VecX<double>& q) {
  VecX<double> beside = q;
  for (int j = 0; j < model.n; ++j) beside[j] += j % 2 ? -0.1 : 0.1;
  FrameKinematics<double> fk(model, frame);
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, model.n);
  MatX<double> both(6, 2 * model.n);
  int k = 0;
  for (const VecX<double>* at : {&q, static_cast<const VecX<double>*>(&beside)}) {
    fk.compute(model, *at);
    fk.jacobian(J);
    both.middleCols(k++ * model.n, model.n) = J;
  }
  return both;
}

// the ranks of Jacobians side by side (jacobians_at_and_beside's columns): at q, and beside it
std::pair<int, int> ranks_at_and_beside(const MatX<double>& both, int n) {
  int rank[2];
  for (int k = 0; k < 2; ++k) {
    Eigen::JacobiSVD<MatX<double>> svd(both.middleCols(k * n, n));
    svd.setThreshold(1e-6);
    rank[k] = static_cast<int>(svd.rank());
  }
  return {rank[0], rank[1]};
}

// the rank of a frame's Jacobian, the higher at q and beside it
int frame_jacobian_rank(const Model& model, const Frame& frame, const VecX<double>& q) {
  const auto [at, beside] = ranks_at_and_beside(jacobians_at_and_beside(model, frame, q), model.n);
  return std::max(at, beside);
}

// where the frame's start is as far out as the arm reaches — its position Jacobian at q of lower
// rank than beside it (a stretched arm) — the direction from the base (the first joint's origin)
// out through the frame's position p; none elsewhere
std::optional<Vec3<double>> outward_at_singular_start(const Model& model, const Frame& frame, const VecX<double>& q,
                                                      const Vec3<double>& p) {
  const auto [at, beside] =
      ranks_at_and_beside(jacobians_at_and_beside(model, frame, q).topRows<3>(), model.n);
  const Vec3<double> out = p - model.link(0).X_tree.r;
  if (at >= beside || !(out.norm() > 1e-9)) return std::nullopt;
  return Vec3<double>(out.normalized());
}

// the direction the frame's position cannot move in, when its position Jacobian has rank 2: at q
// and beside it (a planar arm: the normal of the plane it moves in), or else at q (an arm of two
// joints, whose frame moves on a curved surface, or a start at a singular pose: the plane it moves
// in at first order). Signed towards where the automatic camera looks at such a motion from (−y
// for the x–z plane, −x for y–z, +z, above, for a horizontal plane), so that a circle about it
// runs counter-clockwise in the video
std::optional<Vec3<double>> motion_plane_normal(const Model& model, const Frame& frame, const VecX<double>& q) {
  const MatX<double> both = jacobians_at_and_beside(model, frame, q).topRows<3>();
  for (const MatX<double>& Jp : {both, MatX<double>(both.leftCols(model.n))}) {
    const Eigen::JacobiSVD<MatX<double>> svd(Jp, Eigen::ComputeFullU);
    const VecX<double>& sigma = svd.singularValues();
    if (!(sigma[0] > 0) || (sigma.array() > 1e-6 * sigma[0]).count() != 2) continue;
    Vec3<double> n = svd.matrixU().col(2);
    Eigen::Index axis = 0;
    n.cwiseAbs().maxCoeff(&axis);
    const double towards_camera = axis == 2 ? n[2] : -n[axis];
    return towards_camera < 0 ? Vec3<double>(-n) : n;
  }
  return std::nullopt;
}

std::string joint_list(const std::vector<std::string>& names) {
  std::string list;
  for (const auto& j : names) list += (list.empty() ? "'" : ", '") + j + "'";
  return list;
}

}  // namespace

TaskRun::TaskRun(const Task& task)
    : task_(task),
      // the joints the controller holds (hold.hpp) where the start's keyframe has them, else at
      // qpos0; none with direct torques, which drive every joint
      models_(load_controller_model(task.model, task.q0_rule == "home" ? task.q0_rule : "", !task.direct_torque)),
      imported_(import_model(mj_model(), task.model, import_options(task, models_.controller()))),
      model_(std::make_shared<const Model>(imported_.model)),
      resolved_(resolve(task, model_->n)) {
  const mjModel* m = mj_model();
  if (resolved_.q0.size() == 0) {
    const VecX<double> key = keyframe_qpos(plant_model(), task.q0_rule, task.model);
    resolved_.q0 = held().empty() ? key : held().controlled(key);
  }
  if (task.qref_start) resolved_.controller.q_ref = resolved_.q0;
  set_up_references();

  // the actuators' ranges, narrowed by the task's limit: constraints of the horizon (formulations.md §Torque limits)
  // and the clamp of every torque the plant receives
  lower_ = imported_.actuation.torque_lower.cwiseMax(-resolved_.torque_limit);
  upper_ = imported_.actuation.torque_upper.cwiseMin(resolved_.torque_limit);
  for (int j : model_->unactuated_joints) {
    // a passive joint: no actuator, no torque to bound (the controller's is zero there)
    lower_[j] = -std::numeric_limits<double>::infinity();
    upper_[j] = std::numeric_limits<double>::infinity();
  }
  for (int j : model_->actuated_joints) {
    if (!std::isfinite(lower_[j]) && !std::isfinite(upper_[j])) unbounded_.push_back(model_->joint_names[j]);
  }

  // the controller's settings: the task's, with what needs the model (the horizon's passive
  // forces, formulations.md §Passive forces; its "auto" choices, the same for both formulations,
  // are the Controller's: horizon_setup.hpp)
  plant_ = std::make_unique<Plant>(plant_model(), imported_.actuation, held());
  const std::string timestep_warning = plant_->set_control_period(resolved_.controller.cgmres.dt);
  ControllerSettings& cs = resolved_.controller;
  // kmax "auto": more GMRES iterations for an under-actuated model's stages (task.hpp); the
  // task as run records the number
  const bool kmax_auto = task_.kmax == 0;
  if (kmax_auto) {
    task_.kmax = model_->under_actuated() ? kUnderActuatedKmax : kDefaultKmax;
    cs.cgmres.kmax = task_.kmax;
  }
  cs.q_start = resolved_.q0;
  cs.frame_target = frame_target_;
  (frame_target_ ? cs.frame_reference : cs.joint_reference) = reference_;
  cs.torque_lower = lower_;
  cs.torque_upper = upper_;
  cs.friction_loss = friction_loss(m).cwiseMax(0.0);
  cs.plant_step = plant_->timestep();
  controller_ = std::make_unique<Controller>(model_, cs);
  const HorizonSetup& setup = *controller_->horizon_setup();
  // solver "auto": the task as run records the one the setup chose
  cs.solver = setup.solver;
  task_.solver = to_string(setup.solver);
  if (kmax_auto && model_->under_actuated() && cs.solver == SolverKind::kCgmres) {
    auto_notes_.push_back("kmax \"auto\": " + std::to_string(task_.kmax) +
                          " GMRES iterations per update (an under-actuated model)");
  }

  // what the run does not model, had to change or chose by itself
  if (!models_.full.translations.empty()) notices_.push_back(models_.full.notice());
  if (!held().empty()) notices_.push_back(held().notice(plant_model()));
  notices_.insert(notices_.end(), imported_.notices.begin(), imported_.notices.end());
  notices_.insert(notices_.end(), setup.notes.begin(), setup.notes.end());
  notices_.insert(notices_.end(), auto_notes_.begin(), auto_notes_.end());
  warnings_ = resolved_.warnings;
  if (!unbounded_.empty()) {
    warnings_.push_back("no torque limit is declared for joint(s) " + joint_list(unbounded_) +
                        ": their torques are unbounded (give --torque-limit or the actuators' forcerange)");
  }
  if (!imported_.unmodeled.empty()) {
    std::string list;
    for (const auto& f : imported_.unmodeled) list += (list.empty() ? "" : "; ") + f;
    warnings_.push_back("the plant has features the controller does not model: " + list);
  }
  for (const auto& w : range_violations(m, resolved_.q0, "q0")) warnings_.push_back(w);
  for (const auto& w : range_violations(m, resolved_.controller.q_ref, "qref")) warnings_.push_back(w);
  if (!timestep_warning.empty()) warnings_.push_back(timestep_warning);
}

void TaskRun::set_up_references() {
  const Task& task = task_;
  const std::string where = "task file '" + (task.source.empty() ? std::string("(given)") : task.source) + "'";
  const std::string base_dir = std::filesystem::path(task.source).parent_path().string();
  VecX<double> start = resolved_.controller.q_ref;
  if (task.target) {
    const FrameTask& f = *task.target;
    const mjModel* m = mj_model();
    FrameTarget target;
    target.frame = import_frame(m, f.frame, task.model);
    if (target.frame.link < 0) {
      // no joint moves it: its error is whatever it is at q0, "reached" or not whatever the controller does
      throw std::invalid_argument(where + ", 'target': " + target.frame.name +
                                  " is fixed to the world (the world body, or a body welded to it): no joint moves "
                                  "it, expected a frame on a moving link");
    }
    if (f.position_weight.size() == 1) {
      target.position_weight.setConstant(f.position_weight[0]);
    } else {
      target.position_weight = Eigen::Map<const Vec3<double>>(f.position_weight.data());
    }
    if (f.orientation_weight) {
      target.orientation_weight = *f.orientation_weight;
    } else {
      // "auto": weighted where the arm can hold any orientation of the frame, its Jacobian of rank
      // 6 (taken where it is highest: at q0 and 0.1 rad beside it on every joint, so that a start
      // at a singular pose does not decide it)
      const int rank = frame_jacobian_rank(*model_, target.frame, resolved_.q0);
      target.orientation_weight = rank == 6 ? kAutoOrientationWeight : 0.0;
      if (rank < 6) {
        auto_notes_.push_back("target orientation not weighted (weights.orientation \"auto\"): the frame's Jacobian "
                              "has rank " + std::to_string(rank) + " < 6 with " + std::to_string(model_->n) +
                              " joint(s), the arm cannot hold an arbitrary orientation; give target.weights."
                              "orientation to weigh what it can");
      }
    }
    // "start": the frame's pose at q0 (resolve checked the values given)
    FrameKinematics<double> fk(*model_, target.frame);
    fk.compute(*model_, resolved_.q0);
    target.position = f.position.empty() ? fk.position() : Vec3<double>(Eigen::Map<const Vec3<double>>(f.position.data()));
    target.rotation = f.orientation.empty()
                          ? fk.rotation()
                          : Eigen::Quaterniond(f.orientation[0], f.orientation[1], f.orientation[2], f.orientation[3])
                                .normalized()
                                .toRotationMatrix();
    frame_target_ = target;
    start = target.position;
    tracking_.rotation = target.rotation;
    tracking_.fixed_position = target.position;
    tracking_.site = mj_name2id(m, mjOBJ_SITE, f.frame.c_str());
    if (tracking_.site < 0) tracking_.body = mj_name2id(m, mjOBJ_BODY, f.frame.c_str());
  }
  if (!task.reference.is_null()) {
    const std::optional<Vec3<double>> plane =
        frame_target_ ? motion_plane_normal(*model_, frame_target_->frame, resolved_.q0) : std::nullopt;
    const std::optional<Vec3<double>> outward =
        frame_target_ ? outward_at_singular_start(*model_, frame_target_->frame, resolved_.q0, frame_target_->position)
                      : std::nullopt;
    reference_ = trajectory_from_json(task.reference, where + ", 'reference'", start, base_dir, plane, outward);
    (task.target ? tracking_.position : tracking_.joints) = reference_;
  }
}

ClosedLoopSettings TaskRun::loop_settings() const {
  ClosedLoopSettings ls;
  ls.duration = task_.duration;
  ls.q0 = resolved_.q0;
  ls.v0 = VecX<double>::Zero(n());
  ls.tracking = tracking_;
  ls.latency = resolved_.latency;
  return ls;
}

RunResult TaskRun::run(const std::function<void(const StepRecord&)>& on_step) { return run(loop_settings(), on_step); }

RunResult TaskRun::run(const ClosedLoopSettings& settings, const std::function<void(const StepRecord&)>& on_step) {
  return run_closed_loop(*plant_, *controller_, settings, on_step ? on_step : [](const StepRecord&) {});
}

std::string TaskRun::start_warning(double init_residual) const {
  const ControllerSettings& c = resolved_.controller;
  // (a full-horizon start needs alpha 0: CgmresSettings::validate)
  if (c.solver != SolverKind::kCgmres || !c.cgmres.init_full_horizon || !(init_residual > kStartSolved)) {
    return "";
  }
  std::ostringstream o;
  o.precision(3);
  o << "the start was not solved: |F| = " << init_residual << " after the full-horizon solve (solved: below "
    << kStartSolved << "); C/GMRES tracks from there and may not recover";
  return o.str();
}

RunSummary TaskRun::summary(const RunResult& result, const std::string& log_path) const {
  const int n = this->n();
  const Controller& c = *controller_;
  RunSummary s;
  s.task = task_;
  s.n = n;
  const bool cgmres = c.solver_kind() == SolverKind::kCgmres;
  s.simd_stages = cgmres && (c.nlp().stage_batching() ||
                             (c.problem().costate_lanes() && resolved_.controller.cgmres.shooting == ShootingScheme::kMultiple));
  s.zeta = cgmres ? c.cgmres().settings().zeta : 0.0;
  s.steps = result.steps;
  s.diverged = result.diverged;
  s.diverged_at = result.diverged_at;
  s.divergence_reason = result.divergence_reason;
  const auto& ms = result.update_ms;
  s.mean_update_ms = result.mean_update_ms;
  s.p50_update_ms = percentile(ms, 50);
  s.p95_update_ms = percentile(ms, 95);
  s.max_update_ms = result.updates > 0 ? result.max_update_ms : std::numeric_limits<double>::quiet_NaN();
  s.updates = result.updates;
  s.deadline_misses = result.deadline_misses;
  s.control_period_ms = 1e3 * c.dt();
  s.joint_error_rms = result.joint_error_rms;
  s.rollout_ms = result.mean_phase_ms.rollout;
  s.costate_ms = result.mean_phase_ms.costate;
  s.gmres_ms = result.mean_phase_ms.gmres;
  s.evaluations_per_update = result.evaluations_per_update;
  s.init_residual = result.init_residual;
  s.final_q_error = result.final_q_error;
  s.final_v_norm = result.final_v_norm;
  s.mean_residual = result.mean_residual;
  s.closed_loop_cost = result.closed_loop_cost;
  s.unmodeled = imported_.unmodeled;
  s.notices = notices_;
  s.warnings = warnings_;
  if (const std::string w = start_warning(result.init_residual); !w.empty()) s.warnings.push_back(w);
  s.tracking = result.tracking;
  if (result.tracking) {
    // a frame target: the position error, over the run when it moves, else at the end
    const double e = reference_ ? result.tracking->position_rms : result.tracking->final_position_error;
    s.reached = !s.diverged && e < task_.tracking_tolerance;
  } else {
    s.reached = !s.diverged && s.final_q_error < task_.reach_tolerance;
  }
  s.contact_steps = result.contact_steps;
  s.max_contact_force = result.max_contact_force;
  s.final_disturbance.assign(result.final_disturbance.data(),
                             result.final_disturbance.data() + result.final_disturbance.size());
  const HorizonSetup& chosen = horizon();
  s.implicit_damping = chosen.implicit_damping;
  s.open_loop_rate = chosen.open_loop_rate;
  s.friction_velocity.assign(chosen.friction_velocity.data(), chosen.friction_velocity.data() + n);
  s.Qq.assign(chosen.weights.Qq.data(), chosen.weights.Qq.data() + n);
  s.Qv.assign(chosen.weights.Qv.data(), chosen.weights.Qv.data() + n);
  s.R.assign(chosen.weights.R.data(), chosen.weights.R.data() + n);
  s.unbounded_joints = unbounded_;
  s.joint_names = model_->joint_names;
  for (const JointType type : model_->joint_type) s.joint_types.push_back(type == JointType::kPrismatic ? "slide" : "hinge");
  s.held_joints = held().names;
  s.held_q.assign(held().q.data(), held().q.data() + held().q.size());
  s.torque_lower.assign(lower_.data(), lower_.data() + n);
  s.torque_upper.assign(upper_.data(), upper_.data() + n);
  s.saturated_steps = result.saturated_steps;
  s.saturated_any = result.saturated_any;
  s.max_constraint_violation = result.max_constraint_violation;
  if (s.diverged) s.divergence_hint = divergence_hint(task_, chosen.damping_step_ratio, chosen.open_loop_rate);
  s.model_hash = file_hash(task_.model);  // render checks a log's model and summary by these
  s.log_hash = file_hash(log_path);
  return s;
}

}  // namespace idmpc::mj
