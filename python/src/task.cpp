// Task (the fields of a task file as attributes), its files and its dict form. The dict form
// is the task file's JSON (to_json, task_from_json) through Python's json module.

#include <optional>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "idmpc/experiment/task.hpp"

namespace idmpc::python {
namespace {

Task task_from_dict(const py::handle& d, const Task* base) {
  nlohmann::json j;
  const std::string text = json_dumps(d, "task dict");
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("task dict: expected JSON, got a parse error: ") + e.what());
  }
  return task_from_json(j, "task dict", base ? *base : arm_defaults());
}

}  // namespace

void bind_task(py::module_& m) {
  py::class_<FrameTask>(m, "FrameTask",
                        "A task's frame target as written (the task file's \"target\", docs/tasks.md); TaskRun "
                        "resolves it on the model (TaskRun.frame_target). List fields are copied out: assign a "
                        "whole list.")
      .def(py::init([](std::string frame, std::vector<double> position, std::vector<double> orientation,
                       std::vector<double> position_weight, std::optional<double> orientation_weight) {
             return FrameTask{std::move(frame), std::move(position), std::move(orientation),
                              std::move(position_weight), orientation_weight};
           }),
           py::arg("frame"), py::arg("position") = std::vector<double>{},
           py::arg("orientation") = std::vector<double>{}, py::arg("position_weight") = FrameTask{}.position_weight,
           py::arg("orientation_weight") = py::none())
      .def(py::init<const FrameTask&>(), py::arg("other"), "A copy of other.")
      .def_readwrite("frame", &FrameTask::frame, "site or body name")
      .def_readwrite("position", &FrameTask::position, "[x, y, z] world [m]; empty: the frame's position at q0")
      .def_readwrite("orientation", &FrameTask::orientation,
                     "unit quaternion [w, x, y, z]; empty: the frame's orientation at q0")
      .def_readwrite("position_weight", &FrameTask::position_weight, "1 or 3 values [1/m^2]")
      .def_readwrite("orientation_weight", &FrameTask::orientation_weight,
                     "w_o; None: \"auto\" (100 where the arm can hold any orientation of the frame, else 0)")
      .def("__repr__", [](const FrameTask& t) { return "<idmpc.FrameTask '" + t.frame + "'>"; });

  py::class_<Task>(m, "Task",
                   "An experiment as data: model, initial and target positions, duration, formulation, "
                   "weights and C/GMRES settings (the fields of a task file, docs/tasks.md). Vector fields "
                   "are lists: assign a whole list (appending to the returned copy changes nothing).")
      .def(py::init<>(), "A task with every field empty (zero, false or \"\").")
      .def(py::init<const Task&>(), py::arg("other"), "A copy of other.")
      .def("__copy__", [](const Task& t) { return Task(t); })
      .def("__deepcopy__", [](const Task& t, const py::dict&) { return Task(t); }, py::arg("memo"))
      .def_readwrite("source", &Task::source, "the task file it was read from, for messages")
      .def_readwrite("description", &Task::description)
      .def_readwrite("model", &Task::model, "model path (load_task resolves it against the task file's directory)")
      .def_readwrite("q0_rule", &Task::q0_rule, "\"swingup\", \"home\" or \"\" (then q0 holds the values)")
      .def_readwrite("q0", &Task::q0)
      .def_readwrite("qref", &Task::qref, "target joint positions: one value for all or one per joint")
      .def_readwrite("qref_start", &Task::qref_start, "qref \"q0\": the target is the start configuration")
      .def_property(
          "target", [](const Task& t) { return t.target; },
          [](Task& t, std::optional<FrameTask> target) { t.target = std::move(target); },
          "a FrameTask or None (a copy: assign a whole FrameTask)")
      .def_property(
          "reference", [](const Task& t) { return json_loads(t.reference.dump()); },
          [](Task& t, const py::handle& d) {
            try {
              t.reference = nlohmann::json::parse(json_dumps(d, "reference"));
            } catch (const nlohmann::json::exception& e) {
              throw std::invalid_argument(std::string("reference: expected JSON, got a parse error: ") + e.what());
            }
          },
          "the \"reference\" object as a dict (a copy: assign a whole dict), or None")
      .def_readwrite("tracking_tolerance", &Task::tracking_tolerance,
                     "a frame target counts as reached below this position error [m]")
      .def_readwrite("duration", &Task::duration, "simulated seconds")
      .def_readwrite("formulation", &Task::formulation, "\"fd\" or \"id\"")
      .def_readwrite("derivatives", &Task::derivatives, "\"matrix\" or \"adjoint\"")
      .def_readwrite("simd_stages", &Task::simd_stages)
      .def_readwrite("direct_torque", &Task::direct_torque)
      .def_readwrite("actuate_every_joint", &Task::actuate_every_joint)
      .def_readwrite("implicit_damping", &Task::implicit_damping, "\"on\", \"off\" or \"auto\"")
      .def_readwrite("friction_velocity", &Task::friction_velocity, "empty: \"auto\"")
      .def_readwrite("offset_free", &Task::offset_free)
      .def_readwrite("observer_time_constant", &Task::observer_time_constant)
      .def_readwrite("reach_tolerance", &Task::reach_tolerance)
      .def_readwrite("torque_limit", &Task::torque_limit, "empty: the model's actuator ranges")
      .def_readwrite("Qq", &Task::Qq, "empty: \"auto\"")
      .def_readwrite("Qv", &Task::Qv, "empty: \"auto\"")
      .def_readwrite("Qa", &Task::Qa)
      .def_readwrite("R", &Task::R, "empty: \"auto\"")
      .def_readwrite("Qa_fallback", &Task::Qa_fallback)
      .def_readwrite("N", &Task::N)
      .def_readwrite("kmax", &Task::kmax)
      .def_readwrite("Tf", &Task::Tf)
      .def_readwrite("alpha", &Task::alpha)
      .def_readwrite("dt", &Task::dt)
      .def_readwrite("zeta", &Task::zeta)
      .def_readwrite("h", &Task::h)
      .def_readwrite("init_full_horizon", &Task::init_full_horizon)
      .def_readwrite("shooting", &Task::shooting, "\"single\" or \"multiple\"")
      .def_readwrite("products", &Task::products, "\"difference\" or \"exact\"")
      .def_readwrite("solver", &Task::solver, "\"auto\" (the default), \"cgmres\" or \"riccati\"; a TaskRun's task holds the one chosen")
      .def_readwrite("riccati", &Task::riccati, "the Riccati solver's settings")
      .def_readwrite("latency", &Task::latency,
                     "compute latency in the closed loop: \"none\", \"measured\" or a compute time in ms")
      .def(
          "to_dict", [](const Task& t) { return json_loads(to_json(t).dump()); },
          "The task as a task file's JSON object (what task_from_dict and load_task read).")
      .def("__repr__", [](const Task& t) {
        return "<idmpc.Task " + t.formulation + "/" + t.derivatives + " on '" + t.model + "', " +
               std::to_string(t.duration) + " s>";
      });

  m.def(
      "load_task", [](const std::string& path, const Task* base) { return load_task(path, base); }, py::arg("path"),
      py::arg("base") = nullptr,
      "Reads a task file; the fields it lacks come from base (arm_defaults() if None), its model path is "
      "resolved against the file's directory. Raises ValueError naming the file and field.");
  m.def("task_from_dict", &task_from_dict, py::arg("d"), py::arg("base") = nullptr,
        "A task from a dict in the task file's form over base (arm_defaults() if None); paths are kept as "
        "written. Raises ValueError naming the field.");
  m.def(
      "paper_task", [] { return paper_task(); }, "A copy of the paper's swing-up task (mjcf/paper_swingup.json).");
  m.def(
      "arm_defaults", [] { return arm_defaults(); },
      "A copy of the defaults for real arms, the base of every task file but the paper's.");
  m.def("paper_task_path", &paper_task_path, "The paper's task file shipped with the sources.");
}

}  // namespace idmpc::python
