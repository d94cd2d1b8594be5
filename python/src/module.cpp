// The Python module idmpc: the C++ names, numpy arrays in and out, the same one-line errors
// (std::invalid_argument → ValueError, std::runtime_error → RuntimeError, pybind11's default
// translation).

#include "bindings.hpp"

#include <mujoco/mujoco.h>

namespace idmpc::python {

void check_size(const char* name, Eigen::Index size, int n) {
  if (size != n) {
    throw std::invalid_argument(std::string(name) + " has " + std::to_string(size) + " entries, expected n = " +
                                std::to_string(n));
  }
}

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

std::string json_dumps(const py::handle& obj) {
  // numpy arrays and scalars become lists and numbers
  const py::cpp_function builtin([](const py::handle& o) -> py::object {
    if (py::hasattr(o, "tolist")) return o.attr("tolist")();
    throw py::type_error(std::string("not JSON serializable: ") + py::str(o.get_type()).cast<std::string>());
  });
  return py::module_::import("json").attr("dumps")(obj, py::arg("allow_nan") = false, py::arg("default") = builtin)
      .cast<std::string>();
}

}  // namespace idmpc::python

PYBIND11_MODULE(idmpc, m) {
  m.doc() = "idmpc: nonlinear MPC of robot arms (forward- and inverse-dynamics formulations, C/GMRES) "
            "with MuJoCo as plant";
  m.attr("mujoco_version") = mj_versionString();
  idmpc::python::bind_model(m);
  idmpc::python::bind_task(m);
  idmpc::python::bind_control(m);
}
