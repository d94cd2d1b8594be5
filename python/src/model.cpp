// Model (immutable, shared with the Python object by shared_ptr), load_model, and the dynamics
// kernels on numpy arrays. Each kernel call makes its own Data workspace: no state is shared
// between calls.

#include <memory>
#include <tuple>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::python {
namespace {

// copied from any array-like of floats (the kernels are instantiated for VecX<double>)
using Vector = VecX<double>;

std::shared_ptr<Model> load_model(const std::string& path, bool direct_torque, bool actuate_every_joint) {
  // as the command line loads a task's model: translated for MuJoCo 2.2, then imported
  const mj::LoadedModel loaded = mj::load_model_translated(path);
  mj::ImportOptions options;
  options.direct_torque = direct_torque;
  options.actuate_every_joint = actuate_every_joint;
  options.joint_force_lower = loaded.joint_force_lower;
  options.joint_force_upper = loaded.joint_force_upper;
  return std::make_shared<Model>(mj::import_model(loaded.model.get(), path, options).model);
}

void check_state(const char* algorithm, const Model& model, const Vector& q, const Vector* v = nullptr,
                 const char* x_name = nullptr, const Vector* x = nullptr) {
  const std::string a(algorithm);
  check_size((a + ": q").c_str(), q.size(), model.n);
  if (v) check_size((a + ": v").c_str(), v->size(), model.n);
  if (x) check_size((a + ": " + x_name).c_str(), x->size(), model.n);
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<Model, std::shared_ptr<Model>>(m, "Model",
                                            "The rigid-body model the controllers use (immutable): a tree of n "
                                            "1-DoF joints in topological order, link i carrying joint i.")
      .def_readonly("n", &Model::n, "number of joints (= dofs = links)")
      .def_readonly("name", &Model::name, "the source, for messages")
      .def_readonly("joint_names", &Model::joint_names)
      .def_readonly("parent", &Model::parent, "parent link of each link, -1 for the fixed base")
      .def_readonly("actuated_joints", &Model::actuated_joints, "the joints an actuator drives, increasing")
      .def_readonly("unactuated_joints", &Model::unactuated_joints,
                    "the passive joints no actuator drives (an under-actuated model), increasing")
      .def_property_readonly(
          "joint_types",
          [](const Model& model) {
            std::vector<std::string> types;
            for (const JointType t : model.joint_type) {
              types.push_back(t == JointType::kRevolute ? "revolute" : "prismatic");
            }
            return types;
          },
          "'revolute' or 'prismatic' per joint")
      .def_readonly("gravity", &Model::gravity, "world gravity (zero if disabled)")
      .def_readonly("q_ref", &Model::q_ref, "joint reference (MuJoCo qpos0)")
      .def_readonly("armature", &Model::armature)
      .def_readonly("damping", &Model::damping)
      .def_readonly("stiffness", &Model::stiffness)
      .def_readonly("q_spring", &Model::q_spring)
      .def_readonly("friction", &Model::friction, "friction loss f of the smooth friction f tanh(v/eps)")
      .def_readonly("friction_velocity", &Model::friction_velocity, "eps of the smooth friction")
      .def("__repr__", [](const Model& model) {
        return "<idmpc.Model '" + model.name + "', n = " + std::to_string(model.n) + ">";
      });

  m.def("load_model", &load_model, py::arg("path"), py::arg("direct_torque") = false,
        py::arg("actuate_every_joint") = false,
        "Loads an MJCF or URDF file (MJCF for MuJoCo >= 2.3 translated in memory) and builds the controller's "
        "Model from it. direct_torque: ignore the file's actuators and apply joint torques directly; "
        "actuate_every_joint: confirm that direct torques drive joints no actuator drives. Raises RuntimeError "
        "for a missing or malformed file, ValueError for what the import does not support.");

  m.def(
      "rnea",
      [](const Model& model, const Vector& q, const Vector& v, const Vector& a) -> VecX<double> {
        check_state("rnea", model, q, &v, "a", &a);
        Data data(model);
        return rnea(model, data, q, v, a);
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("a"),
      "Inverse dynamics tau = M(q) a + c(q, v) - passive(q, v) (recursive Newton-Euler).");
  m.def(
      "aba",
      [](const Model& model, const Vector& q, const Vector& v, const Vector& tau) -> VecX<double> {
        check_state("aba", model, q, &v, "tau", &tau);
        Data data(model);
        return aba(model, data, q, v, tau);
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("tau"),
      "Forward dynamics a = M(q)^-1 (tau - c(q, v) + passive(q, v)) (articulated-body algorithm).");
  m.def(
      "crba",
      [](const Model& model, const Vector& q) -> MatX<double> {
        check_state("crba", model, q);
        Data data(model);
        return crba(model, data, q);
      },
      py::arg("model"), py::arg("q"), "Joint-space inertia M(q), n x n with armature (composite-rigid-body algorithm).");
  m.def(
      "rnea_derivatives",
      [](const Model& model, const Vector& q, const Vector& v, const Vector& a) {
        check_state("rnea_derivatives", model, q, &v, "a", &a);
        Data data(model);
        rnea_derivatives(model, data, q, v, a);
        return std::make_tuple(data.dtau_dq, data.dtau_dv, data.M);
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("a"),
      "(dtau_dq, dtau_dv, M): the partial derivatives of rnea(q, v, a); M = dtau_da.");
  m.def(
      "aba_derivatives",
      [](const Model& model, const Vector& q, const Vector& v, const Vector& tau) {
        check_state("aba_derivatives", model, q, &v, "tau", &tau);
        Data data(model);
        aba_derivatives(model, data, q, v, tau);
        return std::make_tuple(data.da_dq, data.da_dv, data.Minv);
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("tau"),
      "(da_dq, da_dv, Minv): the partial derivatives of aba(q, v, tau); Minv = da_dtau.");
}

}  // namespace idmpc::python
