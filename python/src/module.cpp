// The Python module idmpc: the C++ names, numpy arrays in and out, the same one-line errors
// (std::invalid_argument → ValueError, std::runtime_error → RuntimeError, pybind11's default
// translation).

#include "bindings.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>

#include <mujoco/mujoco.h>

#include "idmpc/experiment/data_dir.hpp"

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

namespace {

// The module's own data directory when IDMPC_DATA_DIR does not name one: share/idmpc found from
// the module's file upwards, as installed (<prefix>/lib[/<multiarch>]/python3/dist-packages/
// beside <prefix>/share/idmpc) and in a build tree (<build>/python beside <build>/share/idmpc).
// Not found: data_dir()'s own lookup and error stand.
void find_data_dir() {
  if (std::getenv(kDataDirVariable) != nullptr) return;
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&find_data_dir), &info) == 0 || info.dli_fname == nullptr) return;
  std::error_code ec;
  std::filesystem::path dir = std::filesystem::canonical(info.dli_fname, ec).parent_path();
  if (ec) return;
  for (int up = 0; up < 5 && !dir.empty(); ++up, dir = dir.parent_path()) {
    const std::filesystem::path candidate = dir / "share" / "idmpc";
    if (std::filesystem::is_directory(candidate / "mjcf", ec)) {
      set_data_dir(candidate.string());
      return;
    }
    if (dir == dir.root_path()) return;
  }
}

}  // namespace

}  // namespace idmpc::python

PYBIND11_MODULE(idmpc, m) {
  m.doc() = "idmpc: nonlinear MPC of robot arms (forward- and inverse-dynamics formulations, C/GMRES) "
            "with MuJoCo as plant";
  m.attr("mujoco_version") = mj_versionString();
  idmpc::python::find_data_dir();
  m.def("data_dir", &idmpc::data_dir,
        "The directory holding idmpc's shipped mjcf/ (IDMPC_DATA_DIR, or share/idmpc found from the module)");
  m.def("set_data_dir", &idmpc::set_data_dir, pybind11::arg("dir"),
        "Sets the directory holding mjcf/ for this process (ValueError if it has none)");
  idmpc::python::bind_model(m);
  idmpc::python::bind_tracking(m);
  idmpc::python::bind_task(m);
  idmpc::python::bind_control(m);
}
