#include "app/swingup.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "app/atomic_file.hpp"
#include "app/number_options.hpp"
#include "idmpc/experiment/input_file.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc::app {

CLI::Validator latency_check() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        try {
          value = to_string(parse_latency(value));
          return "";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      "");
}

// true or false, nothing CLI11 would also read as a bool ("" and "-1" as false, "on", "yes", "1")
CLI::Validator true_or_false() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        if (value == "true" || value == "false") return "";
        return "expected true or false, got '" + abbreviate(value) + "'";
      },
      "");
}

void add_task_options(CLI::App& sub, TaskOverrides& o) {
  Task& t = o.values;
  sub.add_option("model", o.model, "MJCF/URDF model file (default: the task's model)");
  sub.add_option("--task", o.task_file,
                 "task file (JSON; default: the paper's swing-up, mjcf/paper_swingup.json)");
  // each option writes into `values`; the applier copies that field into the task
  auto add = [&](CLI::Option* opt, void (*apply)(const Task&, Task&)) { o.given.emplace_back(opt, apply); };
  add(sub.add_option("--formulation", t.formulation, "fd (torques, ABA) or id (accelerations, RNEA)"),
      [](const Task& s, Task& d) { d.formulation = s.formulation; });
  add(sub.add_option("--solver", t.solver,
                     "cgmres (C/GMRES, the paper's), riccati (Gauss-Newton SQP with a Riccati recursion) or auto "
                     "(a task file's default; the paper's task names cgmres): riccati on a fully actuated model, cgmres on an "
                     "under-actuated one, docs/solvers.md"),
      [](const Task& s, Task& d) { d.solver = s.solver; });
  add(sub.add_option("--iterations", t.riccati.iterations,
                     "riccati: SQP iterations per update (1: real-time iteration)"),
      [](const Task& s, Task& d) { d.riccati.iterations = s.riccati.iterations; });
  add(sub.add_option("--derivatives", t.derivatives, "matrix (the paper's) or adjoint (O(n))"),
      [](const Task& s, Task& d) { d.derivatives = s.derivatives; });
  add(sub.add_option("--N", t.N, "horizon steps"), [](const Task& s, Task& d) { d.N = s.N; });
  add(sub.add_option("--kmax", t.kmax, "GMRES iterations per update (default: 10, 20 on an under-actuated model)")
          ->check(CLI::Range(1, std::numeric_limits<int>::max())),
      [](const Task& s, Task& d) { d.kmax = s.kmax; });
  add(sub.add_option("--Tf", t.Tf, "final horizon length [s]"), [](const Task& s, Task& d) { d.Tf = s.Tf; });
  add(sub.add_option("--alpha", t.alpha, "horizon growth rate [1/s]"), [](const Task& s, Task& d) { d.alpha = s.alpha; });
  add(sub.add_option("--dt", t.dt, "sampling period and plant step [s]"), [](const Task& s, Task& d) { d.dt = s.dt; });
  add(sub.add_option("--zeta", t.zeta, "C/GMRES stabilization (0: 1/dt)"), [](const Task& s, Task& d) { d.zeta = s.zeta; });
  add(sub.add_option("--h", t.h, "forward-difference increment of the Frechet products"),
      [](const Task& s, Task& d) { d.h = s.h; });
  add(sub.add_option("--init-full-horizon", t.init_full_horizon,
                     "true: solve the full-horizon problem at t = 0 before the loop (with --alpha 0)")
          ->check(true_or_false()),
      [](const Task& s, Task& d) { d.init_full_horizon = s.init_full_horizon; });
  add(sub.add_option("--shooting", t.shooting,
                     "single (rollout from the measured state) or multiple (states and costates as unknowns, "
                     "condensed)"),
      [](const Task& s, Task& d) { d.shooting = s.shooting; });
  add(sub.add_option("--products", t.products,
                     "difference (the paper's forward differences, increment --h) or exact (dual numbers) "
                     "products of C/GMRES"),
      [](const Task& s, Task& d) { d.products = s.products; });
  add(sub.add_option("--duration", t.duration, "simulated time [s]"),
      [](const Task& s, Task& d) { d.duration = s.duration; });
  add(sub.add_option("--q0", t.q0, "initial joint positions, one per joint"), [](const Task& s, Task& d) {
    d.q0 = s.q0;
    d.q0_rule.clear();
  });
  add(sub.add_option("--qref", t.qref, "target joint positions: a scalar or one per joint"),
      [](const Task& s, Task& d) { d.qref = s.qref; });
  add(sub.add_option("--Qq", t.Qq, "weight on q - qref: scalar or one per joint"), [](const Task& s, Task& d) { d.Qq = s.Qq; });
  add(sub.add_option("--Qv", t.Qv, "weight on v: scalar or one per joint"), [](const Task& s, Task& d) { d.Qv = s.Qv; });
  add(sub.add_option("--Qa", t.Qa, "weight on a (ID only): scalar or one per joint"),
      [](const Task& s, Task& d) { d.Qa = s.Qa; });
  add(sub.add_option("--R", t.R, "weight on torque: scalar or one per joint"), [](const Task& s, Task& d) { d.R = s.R; });
  add(sub.add_option("--torque-limit", t.torque_limit,
                     "|torque| limit: scalar or one per joint (default: the model's actuator ranges)"),
      [](const Task& s, Task& d) { d.torque_limit = s.torque_limit; });
  add(sub.add_flag("--direct-torque", t.direct_torque,
                   "ignore the model's actuators and apply joint torques directly"),
      [](const Task& s, Task& d) { d.direct_torque = s.direct_torque; });
  sub.add_flag("--fallback", o.fallback,
               "ID: if the run diverges with Qa = 0, rerun it with the task's weights.Qa_fallback (the paper's rule)");
  add(sub.add_flag("--actuate-every-joint", t.actuate_every_joint,
                   "with --direct-torque on an under-actuated model: confirm that every joint becomes actuated"),
      [](const Task& s, Task& d) { d.actuate_every_joint = s.actuate_every_joint; });
  add(sub.add_option("--implicit-damping", t.implicit_damping,
                     "integrate joint damping implicitly in the horizon (step Tf/N, needs --alpha 0): on, off, or "
                     "auto (when the explicit step would be unstable)"),
      [](const Task& s, Task& d) { d.implicit_damping = s.implicit_damping; });
  add(sub.add_option("--friction-velocity", t.friction_velocity,
                     "eps of the horizon's smooth friction f*tanh(v/eps): scalar or one per joint (default: auto)"),
      [](const Task& s, Task& d) { d.friction_velocity = s.friction_velocity; });
  add(sub.add_option("--offset-free", t.offset_free,
                     "true: estimate the torque the model misses (disturbance observer) and add it to the horizon")
          ->check(true_or_false()),
      [](const Task& s, Task& d) { d.offset_free = s.offset_free; });
  add(sub.add_option("--observer-time-constant", t.observer_time_constant,
                     "time constant of the disturbance observer's filter [s]"),
      [](const Task& s, Task& d) { d.observer_time_constant = s.observer_time_constant; });
  add(sub.add_option("--reach-tolerance", t.reach_tolerance,
                     "the target is reached when max|q - qref| at the end is below this"),
      [](const Task& s, Task& d) { d.reach_tolerance = s.reach_tolerance; });
  add(sub.add_option("--latency", t.latency,
                     "compute latency in the closed loop: none (the paper's timing: each torque applied one period "
                     "after its measurement), measured (each update's wall time) or a compute time in ms; the "
                     "torque then reaches the plant after the whole plant steps its computation took")
          ->check(latency_check()),
      [](const Task& s, Task& d) { d.latency = to_string(parse_latency(s.latency)); });
  add(sub.add_flag("!--no-simd-stages", t.simd_stages,
                   "evaluate the horizon stages one by one instead of in SIMD lanes (ID; FD matrix; FD "
                   "adjoint under multiple shooting): the paper's arithmetic"),
      [](const Task& s, Task& d) { d.simd_stages = s.simd_stages; });
  require_decimal_numbers(sub);
}

Task make_task(const TaskOverrides& o) {
  Task task = o.task_file.empty() ? paper_task() : load_task(o.task_file);
  if (!o.model.empty()) task.model = o.model;
  for (const auto& [option, apply] : o.given) {
    if (option->count() > 0) apply(o.values, task);
  }
  return task;
}

namespace {

// The progress lines of a run: every kProgressPeriod of wall time, from the controller's start
// (between its iterations) and from the steps
class Progress {
 public:
  using Clock = std::chrono::steady_clock;
  Progress(const mj::TaskRun& run, double duration, double period)
      : run_(run),
        duration_(duration),
        period_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period))),
        next_(begin_ + period_) {}

  // during the start, before the first step
  void starting() {
    if (!due()) return;
    std::ostringstream o;
    o << "idmpc: still solving the start at t = 0 (" << std::fixed << std::setprecision(1) << seconds_since(begin_)
      << " s so far)";
    std::cerr << o.str() << "\n";
  }
  void step(const mj::StepRecord& s) {
    if (steps_++ == 0) window_ = Clock::now();  // the rate counts from the first step, not the start
    if (!due()) return;
    const double wall = seconds_since(window_);
    const double rate = wall > 0 ? static_cast<double>(steps_ - window_steps_) / wall : 0.0;
    window_ = Clock::now();
    window_steps_ = steps_;
    std::ostringstream o;
    o << "idmpc: t = " << std::setprecision(3) << s.t << " s of " << duration_ << " s (" << std::fixed
      << std::setprecision(0) << 100 * s.t / duration_ << " %), ";
    if (s.frame_position && s.frame_target) {
      o << "frame position error " << std::setprecision(2) << 1e3 * (*s.frame_position - *s.frame_target).norm()
        << " mm";
    } else {
      o << "max|q - qref| " << std::defaultfloat << std::setprecision(3)
        << (s.q - run_.controller().q_ref()).cwiseAbs().maxCoeff() << " rad";
    }
    o << ", " << std::fixed << std::setprecision(0) << rate << " steps/s";
    std::cerr << o.str() << "\n";
  }

 private:
  static double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
  bool due() {
    const Clock::time_point now = Clock::now();
    if (now < next_) return false;
    next_ = now + period_;
    return true;
  }

  const mj::TaskRun& run_;
  double duration_;
  Clock::duration period_;
  Clock::time_point begin_ = Clock::now();
  Clock::time_point next_;
  Clock::time_point window_;  ///< since the last progress line (or the first step): the rate's window
  long steps_ = 0, window_steps_ = 0;
};

SwingupOutcome run_once(const Task& task, const std::string& log_path, const RunMessages& messages) {
  // everything is validated before any output is opened
  mj::TaskRun run(task);
  if (messages.notices) {
    for (const auto& w : run.notices()) std::cerr << "idmpc: " << w << "\n";
  }
  for (const auto& w : run.warnings()) std::cerr << "idmpc: warning: " << w << "\n";
  const bool limited = (run.torque_lower().array().isFinite() || run.torque_upper().array().isFinite()).any();

  // the log streams to a temporary file, renamed once the run has ended
  std::optional<AtomicFile> log;
  std::optional<RunLogWriter> writer;
  if (!log_path.empty()) {
    log.emplace(log_path);
    writer.emplace(log->stream(), run.n(), limited, run.frame_target().has_value());
  }
  std::optional<Progress> progress;
  if (messages.progress_period >= 0) {
    progress.emplace(run, task.duration, messages.progress_period);
    run.controller().set_interrupt_check([&progress] { progress->starting(); });
  }
  bool first = true;
  auto on_step = [&](const mj::StepRecord& s) {
    if (first) {
      // the start's own residual, said as the loop begins (the first update starts from it)
      first = false;
      if (const std::string w = run.start_warning(run.controller().start_residual()); !w.empty()) {
        std::cerr << "idmpc: warning: " << w << "\n";
      }
    }
    if (writer) writer->row(s.t, s.q, s.v, s.u, s.u_commanded, s.residual, s.update_ms, s.frame_position, s.frame_target);
    if (progress) progress->step(s);
  };
  mj::RunResult result = run.run(on_step);
  run.controller().set_interrupt_check({});
  if (log) log->commit();
  RunSummary summary = run.summary(result, log_path);
  return SwingupOutcome{std::move(result), std::move(summary)};
}

}  // namespace

SwingupOutcome run_swingup(const Task& task, const std::string& log_path, bool fallback,
                           const RunMessages& messages) {
  SwingupOutcome out = run_once(task, log_path, messages);
  if (!(fallback && out.summary.diverged && task.formulation == "id" && without_Qa(task) && task.Qa_fallback > 0)) {
    return out;
  }
  // the paper's rule: ID that fails with Q_a = 0 is rerun with the fallback Q_a
  std::ostringstream said;
  said << "ID diverged at t = " << out.summary.diverged_at << " s with Qa = 0 (" << out.summary.divergence_reason
       << "); rerun with Qa = " << task.Qa_fallback << " (weights.Qa_fallback)";
  std::cerr << "idmpc: warning: " << said.str() << "\n";
  Task again = task;
  again.Qa = {task.Qa_fallback};
  out = run_once(again, log_path, messages);
  out.summary.warnings.push_back(said.str());
  return out;
}

void write_json(const nlohmann::json& j, const std::string& path) {
  AtomicFile f(path);
  f.stream() << j.dump(2) << '\n';
  f.commit();
}

std::string human_summary(const RunSummary& s) {
  std::ostringstream o;
  o << std::setprecision(4);
  const bool riccati = s.task.solver == "riccati";
  o << s.label().substr(0, s.label().find(')') + 1) << " on " << s.task.model << ": n = " << s.n
    << ", N = " << s.task.N << ", "
    << (riccati ? "iterations = " + std::to_string(s.task.riccati.iterations) : "kmax = " + std::to_string(s.task.kmax))
    << ", " << s.task.duration << " s\n";
  if (s.diverged) {
    o << "  DIVERGED at t = " << s.diverged_at << " s: " << s.divergence_reason << "\n";
    if (!s.divergence_hint.empty()) o << "  hint: " << s.divergence_hint << "\n";
  } else {
    o << "  completed " << s.steps << " control steps without divergence\n";
  }
  o << "  update time [ms]: mean " << s.mean_update_ms << ", p50 " << s.p50_update_ms << ", p95 "
    << s.p95_update_ms << ", max " << s.max_update_ms << "  (" << s.evaluations_per_update
    << (riccati ? " linearizations and line-search evaluations)\n" : " F evaluations)\n");
  if (s.task.latency != "none" || s.deadline_misses > 0) {
    o << "  compute latency " << s.task.latency << ": " << s.deadline_misses
      << " update(s) took longer than the control period of " << s.control_period_ms << " ms (deadline misses)\n";
  }
  if (riccati) {
    o << "  phases [ms]: local models " << s.rollout_ms << ", Riccati recursion " << s.costate_ms << ", rest "
      << s.gmres_ms << "\n";
  } else {
    o << "  phases [ms]: rollout " << s.rollout_ms << ", costate " << s.costate_ms << ", gmres " << s.gmres_ms << "\n";
  }
  o << "  final max|q - qref| = " << s.final_q_error << ", |v| = " << s.final_v_norm
    << ", mean residual " << s.mean_residual << "\n";
  if (s.tracking) {
    const TrackingResult& r = *s.tracking;
    const bool moving = !s.task.reference.is_null();
    o << "  frame '" << s.task.target->frame << "': position error RMS " << 1e3 * r.position_rms << " mm, max "
      << 1e3 * r.position_max << " mm, final " << 1e3 * r.final_position_error << " mm; orientation error RMS "
      << r.orientation_rms * 180 / M_PI << " deg, max " << r.orientation_max * 180 / M_PI << " deg\n";
    o << "  target " << (s.reached ? "REACHED" : "NOT reached") << " (position error "
      << (moving ? "RMS" : "at the end") << " < " << 1e3 * s.task.tracking_tolerance << " mm)\n";
  } else {
    o << "  target " << (s.reached ? "REACHED" : "NOT reached") << " (max|q - qref| < " << s.task.reach_tolerance
      << " at the end)\n";
  }
  if (!s.final_disturbance.empty() && s.task.offset_free) {
    double largest = 0;
    for (double d : s.final_disturbance) largest = std::max(largest, std::abs(d));
    o << "  offset-free tracking: estimated unmodeled torque up to " << largest << " at the end\n";
  }
  o << "  contacts on " << s.contact_steps << " of " << s.steps << " steps";
  if (s.contact_steps > 0) o << ", largest normal force " << s.max_contact_force << " N";
  o << "\n";
  if (!s.unbounded_joints.empty()) {
    o << "  no torque limit declared for " << s.unbounded_joints.size() << " joint(s): torques unbounded\n";
  }
  if (s.saturated_any > 0) {
    o << "  torque saturated on " << s.saturated_any << " of " << s.steps << " steps (per joint:";
    for (long k : s.saturated_steps) o << ' ' << k;
    o << ")\n";
  }
  if (std::isfinite(s.max_constraint_violation) && s.max_constraint_violation > 0) {
    o << "  the OCP's torques left their bounds by up to " << s.max_constraint_violation << " N m\n";
  } else if (!std::isfinite(s.max_constraint_violation)) {
    o << "  the OCP's torques became non-finite\n";
  }
  return o.str();
}

}  // namespace idmpc::app
