// The controller, the MuJoCo plant and a task's closed loop (TaskRun). run() collects the
// per-step records in C++ with the GIL released and converts them to numpy arrays once.

#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc::python {
namespace {

using Vector = VecX<double>;

// the per-step rows of a run, as the closed loop hands them over
struct Rows {
  int n = 0;
  std::vector<double> t, q, v, u, u_commanded, residual, update_ms;
  std::vector<double> frame_position, frame_target;  // with a frame target: 3 per step

  void add(const mj::StepRecord& s) {
    t.push_back(s.t);
    q.insert(q.end(), s.q.data(), s.q.data() + n);
    v.insert(v.end(), s.v.data(), s.v.data() + n);
    u.insert(u.end(), s.u.data(), s.u.data() + n);
    u_commanded.insert(u_commanded.end(), s.u_commanded.data(), s.u_commanded.data() + n);
    residual.push_back(s.residual);
    update_ms.push_back(s.update_ms);
    if (s.frame_position && s.frame_target) {
      frame_position.insert(frame_position.end(), s.frame_position->data(), s.frame_position->data() + 3);
      frame_target.insert(frame_target.end(), s.frame_target->data(), s.frame_target->data() + 3);
    }
  }
};

// steps × columns (columns = 0: a vector of length steps), C order
py::array_t<double> to_array(const std::vector<double>& x, size_t columns = 0) {
  const auto steps = static_cast<py::ssize_t>(columns ? x.size() / columns : x.size());
  py::array_t<double> a = columns ? py::array_t<double>({steps, static_cast<py::ssize_t>(columns)})
                                  : py::array_t<double>(steps);
  if (!x.empty()) std::memcpy(a.mutable_data(), x.data(), x.size() * sizeof(double));
  return a;
}

// thrown out of the closed loop when Python has a signal to handle (Ctrl-C): its exception
// (KeyboardInterrupt) is set, and raised once the GIL is back
struct Interrupted {};

// how often a long call lets Python handle its signals: a step of a long run takes a fraction
// of a millisecond, taking the GIL every step would cost more than the step
constexpr auto kSignalCheckPeriod = std::chrono::milliseconds(50);

// While it lives (the GIL released): poll() lets Python handle its signals every
// kSignalCheckPeriod, and the controller's start polls between its iterations; a signal whose
// handler raises (Ctrl-C: KeyboardInterrupt) throws Interrupted out of the call
class SignalPolling {
 public:
  explicit SignalPolling(Controller& controller) : controller_(controller) {
    controller_.set_interrupt_check([this] { poll(); });
  }
  SignalPolling(const SignalPolling&) = delete;
  SignalPolling& operator=(const SignalPolling&) = delete;
  ~SignalPolling() { controller_.set_interrupt_check({}); }

  void poll() {
    const auto now = std::chrono::steady_clock::now();
    if (now < next_check_) return;
    next_check_ = now + kSignalCheckPeriod;
    py::gil_scoped_acquire acquire;
    if (PyErr_CheckSignals() != 0) throw Interrupted{};
  }

 private:
  Controller& controller_;
  std::chrono::steady_clock::time_point next_check_ = std::chrono::steady_clock::now() + kSignalCheckPeriod;
};

py::dict run_task_run(mj::TaskRun& run) {
  Rows rows;
  rows.n = run.n();
  mj::RunResult result;
  RunSummary summary;
  try {
    py::gil_scoped_release release;
    SignalPolling signals(run.controller());
    result = run.run([&rows, &signals](const mj::StepRecord& s) {
      rows.add(s);
      signals.poll();
    });
    summary = run.summary(result);
  } catch (const Interrupted&) {
    throw py::error_already_set();  // the signal handler's exception, KeyboardInterrupt for Ctrl-C
  }
  const auto n = static_cast<size_t>(rows.n);
  py::dict d;
  d["t"] = to_array(rows.t);
  d["q"] = to_array(rows.q, n);
  d["v"] = to_array(rows.v, n);
  d["u"] = to_array(rows.u, n);
  d["u_commanded"] = to_array(rows.u_commanded, n);
  d["residual"] = to_array(rows.residual);
  d["update_ms"] = to_array(rows.update_ms);
  if (run.frame_target()) {
    d["frame_position"] = to_array(rows.frame_position, 3);
    d["frame_target"] = to_array(rows.frame_target, 3);
  }
  d["updates"] = result.updates;
  d["summary"] = json_loads(to_json(summary).dump());
  return d;
}

std::shared_ptr<Model> mutable_model(std::shared_ptr<const Model> model) {
  // Model's members are all const: the Python object may share it without a copy
  return std::const_pointer_cast<Model>(std::move(model));
}

// trajectories are immutable for Python too (no setters): shared without a copy
std::shared_ptr<Trajectory> mutable_trajectory(std::shared_ptr<const Trajectory> trajectory) {
  return std::const_pointer_cast<Trajectory>(std::move(trajectory));
}

}  // namespace

void bind_control(py::module_& m) {
  py::class_<CgmresSettings>(m, "CgmresSettings", "C/GMRES settings (the task file's \"cgmres\" object).")
      .def(py::init<>())
      .def_readwrite("kmax", &CgmresSettings::kmax, "GMRES iterations per update")
      .def_property(
          "shooting", [](const CgmresSettings& s) { return to_string(s.shooting); },
          [](CgmresSettings& s, const std::string& x) { s.shooting = parse_shooting(x); }, "\"single\" or \"multiple\"")
      .def_property(
          "products", [](const CgmresSettings& s) { return to_string(s.products); },
          [](CgmresSettings& s, const std::string& x) { s.products = parse_products(x); },
          "\"difference\" (forward differences, increment h) or \"exact\" (dual numbers)")
      .def_readwrite("Tf", &CgmresSettings::Tf, "horizon length T_f [s]")
      .def_readwrite("alpha", &CgmresSettings::alpha, "horizon growth rate: T(t) = T_f (1 - exp(-alpha t))")
      .def_readwrite("dt", &CgmresSettings::dt, "sampling period [s]")
      .def_readwrite("zeta", &CgmresSettings::zeta, "stabilization; 0 means 1/dt")
      .def_readwrite("h", &CgmresSettings::h, "forward-difference increment")
      .def_readwrite("init_iterations", &CgmresSettings::init_iterations)
      .def_readwrite("init_tolerance", &CgmresSettings::init_tolerance)
      .def_readwrite("init_full_horizon", &CgmresSettings::init_full_horizon)
      .def("validate", &CgmresSettings::validate, "Raises ValueError naming the first bad setting.");

  py::class_<OcpWeights>(m, "OcpWeights", "Weights of the stage cost: Qq, Qv, Qa, R (one per joint; Qa may be empty).")
      .def(py::init<>())
      .def_readwrite("Qq", &OcpWeights::Qq)
      .def_readwrite("Qv", &OcpWeights::Qv)
      .def_readwrite("Qa", &OcpWeights::Qa)
      .def_readwrite("R", &OcpWeights::R);

  py::class_<RiccatiSettings>(m, "RiccatiSettings",
                              "The Riccati solver's settings (the task file's \"riccati\" object).")
      .def(py::init<>())
      .def_readwrite("iterations", &RiccatiSettings::iterations, "SQP iterations per update (1: real-time iteration)")
      .def_readwrite("tolerance", &RiccatiSettings::tolerance, "fewer iterations below this KKT residual (0: all)")
      .def_readwrite("init_iterations", &RiccatiSettings::init_iterations, "SQP iterations of the start, at most")
      .def_readwrite("init_tolerance", &RiccatiSettings::init_tolerance, "the start's KKT residual")
      .def_readwrite("barrier", &RiccatiSettings::barrier, "weight of the torque limits' barrier")
      .def_readwrite("regularization", &RiccatiSettings::regularization)
      .def_readwrite("line_search", &RiccatiSettings::line_search, "line search in the updates too")
      .def("validate", &RiccatiSettings::validate, "Raises ValueError naming the first bad setting.");

  py::class_<ControllerSettings>(m, "ControllerSettings",
                                 "Everything a Controller is built from besides its model; vectors have one entry "
                                 "per joint, checked by the Controller's constructor.")
      .def(py::init<>())
      .def_property(
          "formulation", [](const ControllerSettings& s) { return to_string(s.formulation); },
          [](ControllerSettings& s, const std::string& x) { s.formulation = parse_formulation(x); }, "\"fd\" or \"id\"")
      .def_property(
          "derivatives", [](const ControllerSettings& s) { return to_string(s.derivatives); },
          [](ControllerSettings& s, const std::string& x) { s.derivatives = parse_derivative_mode(x); },
          "\"matrix\" or \"adjoint\"")
      .def_readwrite("N", &ControllerSettings::N, "horizon stages")
      .def_property(
          "solver", [](const ControllerSettings& s) { return to_string(s.solver); },
          [](ControllerSettings& s, const std::string& x) { s.solver = parse_solver(x); },
          "\"cgmres\" (the default), \"riccati\" or \"auto\" (the Riccati recursion on a fully actuated model, "
          "C/GMRES on an under-actuated one; Controller.solver says which)")
      .def_readwrite("cgmres", &ControllerSettings::cgmres)
      .def_readwrite("riccati", &ControllerSettings::riccati)
      .def_readwrite("weights", &ControllerSettings::weights)
      .def_readwrite("q_ref", &ControllerSettings::q_ref)
      .def_property(
          "joint_reference", [](const ControllerSettings& s) { return mutable_trajectory(s.joint_reference); },
          [](ControllerSettings& s, std::shared_ptr<Trajectory> r) { s.joint_reference = std::move(r); },
          "a moving joint target q_ref(t), n values (its rate the velocity reference); None: q_ref")
      .def_property(
          "frame_target", [](const ControllerSettings& s) { return s.frame_target; },
          [](ControllerSettings& s, std::optional<FrameTarget> target) { s.frame_target = std::move(target); },
          "a FrameTarget beside the joint terms (Q_q and q_ref then weigh the posture), or None (a copy: "
          "assign a whole FrameTarget)")
      .def_property(
          "frame_reference", [](const ControllerSettings& s) { return mutable_trajectory(s.frame_reference); },
          [](ControllerSettings& s, std::shared_ptr<Trajectory> r) { s.frame_reference = std::move(r); },
          "the frame target's position moving as p_ref(t) (3 values); None: frame_target.position")
      .def_readwrite("torque_lower", &ControllerSettings::torque_lower, "empty: unbounded; -inf per joint: unbounded")
      .def_readwrite("torque_upper", &ControllerSettings::torque_upper, "empty: unbounded; +inf per joint: unbounded")
      .def_readwrite("limits_in_horizon", &ControllerSettings::limits_in_horizon,
                     "false: the limits only clamp the returned torque")
      .def_readwrite("observer_time_constant", &ControllerSettings::observer_time_constant,
                     "disturbance observer [s]; 0: off")
      .def_readwrite("simd_stages", &ControllerSettings::simd_stages)
      .def_readwrite("q_start", &ControllerSettings::q_start,
                     "the start the automatic choices consider beside q_ref; empty: q_ref alone")
      .def_readwrite("friction_loss", &ControllerSettings::friction_loss,
                     "the plant's dry friction per joint, modelled as f*tanh(v/eps); empty: the model's own")
      .def_readwrite("friction_velocity", &ControllerSettings::friction_velocity,
                     "eps of the smooth friction per joint; empty: \"auto\"")
      .def_property(
          "implicit_damping", [](const ControllerSettings& s) { return to_string(s.implicit_damping); },
          [](ControllerSettings& s, const std::string& x) { s.implicit_damping = parse_implicit_damping(x); },
          "joint damping over the horizon step: \"off\", \"on\" or \"auto\"")
      .def_readwrite("plant_step", &ControllerSettings::plant_step,
                     "the plant's integration step [s], over which the torque rule takes the damping implicitly; 0: "
                     "explicit");

  py::class_<Controller>(m, "Controller",
                         "The NMPC controller: the problem (FD or ID formulation), C/GMRES and the torque rule. "
                         "initialize(q, v) once, then update(t, q, v) every dt; torque is what to apply next. What it has "
                         "(sizes, the latest results, the target and limits) are read-only attributes, what it "
                         "does are methods.")
      .def(py::init([](std::shared_ptr<Model> model, const ControllerSettings& settings) {
             return std::make_unique<Controller>(std::move(model), settings);
           }),
           py::arg("model"), py::arg("settings"))
      .def_property_readonly("n", &Controller::n)
      .def_property_readonly("dt", &Controller::dt)
      .def_property_readonly(
          "solver", [](const Controller& c) { return to_string(c.solver_kind()); },
          "the solver it runs, \"cgmres\" or \"riccati\" (settings' \"auto\" resolved)")
      .def(
          "initialize",
          [](Controller& c, const Vector& q, const Vector& v) -> Vector {
            check_size("initialize: q", q.size(), c.n());
            check_size("initialize: v", v.size(), c.n());
            try {
              py::gil_scoped_release release;  // a full-horizon start may take seconds
              SignalPolling signals(c);
              return c.initialize(q, v);
            } catch (const Interrupted&) {
              throw py::error_already_set();  // KeyboardInterrupt for Ctrl-C
            }
          },
          py::arg("q"), py::arg("v"),
          "Zero-horizon initialization from the measured state; returns the torque for the first period. "
          "Ctrl-C interrupts a long start (KeyboardInterrupt); initialize again before updating.")
      .def(
          "update",
          [](Controller& c, double t, const Vector& q, const Vector& v) {
            check_size("update: q", q.size(), c.n());
            check_size("update: v", v.size(), c.n());
            py::gil_scoped_release release;
            return c.update(t, q, v);
          },
          py::arg("t"), py::arg("q"), py::arg("v"),
          "One control update at time t; True and torque for the next period, or False and failure.")
      .def_property_readonly("torque", [](const Controller& c) -> Vector { return c.torque(); }, "the torque to apply (within the limits)")
      .def_property_readonly("commanded_torque", [](const Controller& c) -> Vector { return c.commanded_torque(); },
           "the torque before clamping to the limits")
      .def_property_readonly("failure", &Controller::failure, "why the last initialize/update failed, or \"\"")
      .def_property_readonly("residual_norm", &Controller::residual_norm)
      .def_property_readonly("constraint_violation", &Controller::constraint_violation)
      .def_property_readonly("disturbance", [](const Controller& c) -> Vector { return c.disturbance(); },
           "the observer's estimate of the unmodeled joint torque")
      .def_property_readonly("applied_acceleration", [](const Controller& c) -> Vector { return c.applied_acceleration(); })
      .def_property_readonly("q_ref", [](const Controller& c) -> Vector { return c.q_ref(); })
      .def(
          "set_target",
          [](Controller& c, const Vector& q_ref) {
            check_size("set_target: q_ref", q_ref.size(), c.n());
            c.set_target(q_ref);
          },
          py::arg("q_ref"), "A new target from the next update on.")
      .def("set_frame_target", &Controller::set_frame_target, py::arg("position"), py::arg("rotation"),
           "A new pose for the frame target from the next update on (a frame reference, if any, keeps moving "
           "the position). ValueError without a frame target, for a non-finite position or a rotation that is "
           "not one.")
      .def_property_readonly(
          "frame_target", [](const Controller& c) { return c.problem().terms().frame_target(); },
          "the frame target the horizon weighs (a copy), or None")
      .def("set_torque_limits", &Controller::set_torque_limits, py::arg("lower"), py::arg("upper"))
      .def_property_readonly("torque_lower", [](const Controller& c) -> Vector { return c.torque_lower(); })
      .def_property_readonly("torque_upper", [](const Controller& c) -> Vector { return c.torque_upper(); })
      .def("set_disturbance_observer", &Controller::set_disturbance_observer, py::arg("time_constant"));

  py::class_<mj::Plant>(m, "Plant",
                        "The MuJoCo simulation the controller drives, one control period per step: its state and "
                        "sizes are read-only attributes, reset, step and set_control_period methods.")
      .def_property_readonly("nv", &mj::Plant::nv)
      .def_property_readonly("timestep", &mj::Plant::timestep, "MuJoCo's timestep [s]")
      .def_property_readonly("substeps", &mj::Plant::substeps, "MuJoCo steps per control period")
      .def("set_control_period", &mj::Plant::set_control_period, py::arg("dt"),
           "Sets the control period; returns a warning if the timestep had to change, else \"\".")
      .def(
          "reset",
          [](mj::Plant& p, const Vector& q, const Vector& v) {
            check_size("reset: q", q.size(), p.nv());
            check_size("reset: v", v.size(), p.nv());
            p.reset(q, v);
          },
          py::arg("q"), py::arg("v"))
      .def(
          "step",
          [](mj::Plant& p, const Vector& tau) {
            check_size("step: tau", tau.size(), p.nv());
            std::string reason;
            const bool ok = p.step(tau, &reason);
            return std::make_pair(ok, reason);
          },
          py::arg("tau"), "Applies tau for one control period: (True, \"\"), or (False, why the simulation failed).")
      .def_property_readonly("q", [](const mj::Plant& p) -> Vector { return p.q(); })
      .def_property_readonly("v", [](const mj::Plant& p) -> Vector { return p.v(); })
      .def_property_readonly(
          "full_q", [](const mj::Plant& p) -> Vector { return p.full_q(); },
          "the whole model's qpos, the joints the controller holds (a gripper's fingers) included; q and v are "
          "the controller's joints")
      .def_property_readonly("time", &mj::Plant::time)
      .def_property_readonly("contact_steps", &mj::Plant::contact_steps)
      .def_property_readonly("max_contact_force", &mj::Plant::max_contact_force);

  py::class_<mj::TaskRun>(m, "TaskRun",
                          "A task on its MuJoCo model, ready to run: the plant and the controller built as the "
                          "command line builds them. Not thread-safe: one thread per TaskRun.")
      .def(py::init<const Task&>(), py::arg("task"))
      .def_property_readonly(
          "task", [](const mj::TaskRun& r) { return r.task(); }, "a copy of the task it runs")
      .def_property_readonly("controller", py::overload_cast<>(&mj::TaskRun::controller),
                             py::return_value_policy::reference_internal)
      .def_property_readonly("plant", &mj::TaskRun::plant, py::return_value_policy::reference_internal)
      .def_property_readonly("model", [](const mj::TaskRun& r) { return mutable_model(r.shared_model()); },
                             "the imported model (the plant's joints, without friction)")
      .def_property_readonly(
          "settings", [](const mj::TaskRun& r) { return r.settings(); },
          "the controller's settings (a copy): Controller(run.model, run.settings) is the controller this run "
          "drives")
      .def_property_readonly("n", &mj::TaskRun::n)
      .def_property_readonly("q0", [](const mj::TaskRun& r) -> Vector { return r.q0(); })
      .def_property_readonly("torque_lower", [](const mj::TaskRun& r) -> Vector { return r.torque_lower(); })
      .def_property_readonly("torque_upper", [](const mj::TaskRun& r) -> Vector { return r.torque_upper(); })
      .def_property_readonly("unbounded_joints", &mj::TaskRun::unbounded_joints)
      .def_property_readonly(
          "frame_target", [](const mj::TaskRun& r) { return r.frame_target(); },
          "the task's frame target resolved on the model (\"start\" filled in; a copy), or None")
      .def_property_readonly(
          "reference", [](const mj::TaskRun& r) { return mutable_trajectory(r.reference()); },
          "the task's moving reference (the frame target's position with a target, else the joint target), "
          "or None")
      .def(
          "frame",
          [](const mj::TaskRun& r, const std::string& name) {
            return mj::import_frame(r.mj_model(), name, r.task().model);
          },
          py::arg("name"), "The Frame of the site or body called name on the run's model (as load_frame).")
      .def_property_readonly("notices", &mj::TaskRun::notices)
      .def_property_readonly("warnings", &mj::TaskRun::warnings)
      .def("run", &run_task_run,
           "The task's closed loop from (q0, 0) for task.duration; a dict of numpy arrays t, residual, update_ms "
           "(steps,), q, v, u, u_commanded (steps x n), with a frame target frame_position and frame_target "
           "(steps x 3: the frame measured on the plant and its target at t), updates (the successful updates) "
           "and summary (the run summary as a dict, with \"tracking\" for a frame target). The GIL is released "
           "while it runs.");

  m.def(
      "run_task", [](const Task& task) { mj::TaskRun run(task); return run_task_run(run); }, py::arg("task"),
      "TaskRun(task).run(): one sweep cell (a task with its settings). `idmpc sweep` runs whole sweeps.");
}

}  // namespace idmpc::python
