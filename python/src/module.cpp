// The Python module idmpc: the C++ names, numpy arrays in and out, the same one-line errors
// (std::invalid_argument → ValueError, std::runtime_error → RuntimeError, pybind11's default
// translation).

#include "bindings.hpp"

#include <dlfcn.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <mujoco/mujoco.h>

#include "idmpc/experiment/data_dir.hpp"
#include "idmpc/model/checks.hpp"

namespace idmpc::python {

void check_size(const char* name, Eigen::Index size, int n) {
  if (size != n) {
    throw std::invalid_argument(std::string(name) + " has " + std::to_string(size) + " entries, expected n = " +
                                std::to_string(n));
  }
}

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

namespace {

// the place of the first number that is not finite in nested dicts and lists, e.g. "cgmres.Tf"
// or "q0[2]" ("" for obj itself), and its text; false if there is none
bool find_non_finite(const py::handle& obj, const std::string& place, std::string& found, std::string& text) {
  if (py::isinstance<py::dict>(obj)) {
    for (const auto& item : py::reinterpret_borrow<py::dict>(obj)) {
      const std::string key = py::str(item.first).cast<std::string>();
      if (find_non_finite(item.second, place.empty() ? key : place + "." + key, found, text)) return true;
    }
    return false;
  }
  if (py::isinstance<py::list>(obj) || py::isinstance<py::tuple>(obj)) {
    size_t i = 0;
    for (const auto& x : obj) {
      if (find_non_finite(x, place + "[" + std::to_string(i++) + "]", found, text)) return true;
    }
    return false;
  }
  if (py::isinstance<py::float_>(obj) || py::hasattr(obj, "tolist")) {
    const py::object value = py::isinstance<py::float_>(obj) ? py::reinterpret_borrow<py::object>(obj)
                                                             : obj.attr("tolist")();
    if (!py::isinstance<py::float_>(value)) return find_non_finite(value, place, found, text);
    if (std::isfinite(value.cast<double>())) return false;
    found = place;
    text = py::repr(value).cast<std::string>();
    return true;
  }
  return false;
}

}  // namespace

std::string json_dumps(const py::handle& obj, const std::string& where) {
  // numpy arrays and scalars become lists and numbers
  const py::cpp_function builtin([](const py::handle& o) -> py::object {
    if (py::hasattr(o, "tolist")) return o.attr("tolist")();
    throw py::type_error(std::string("not JSON serializable: ") + py::str(o.get_type()).cast<std::string>());
  });
  try {
    return py::module_::import("json").attr("dumps")(obj, py::arg("allow_nan") = false, py::arg("default") = builtin)
        .cast<std::string>();
  } catch (py::error_already_set& e) {
    // JSON has no NaN or infinity: Python's own words ("Out of range float values are not JSON
    // compliant") name neither the field nor the value
    std::string place, text;
    if (!e.matches(PyExc_ValueError) || !find_non_finite(obj, "", place, text)) throw;
    throw std::invalid_argument(where + ": " + (place.empty() ? std::string() : "field '" + place + "': ") +
                                "expected a finite number, got " + text);
  }
}

namespace {

// a failed debug check (IDMPC_DEBUG_CHECK, compiled in debug and sanitizer builds) raises
// idmpc.DebugCheckError instead of aborting the interpreter
[[noreturn]] void raise_debug_check(const char* text) { throw DebugCheckFailed(text); }

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
  // numpy first: the bindings cannot be made without it, and pybind11 would only say
  // "initialization failed"
  try {
    pybind11::module_::import("numpy");
  } catch (pybind11::error_already_set&) {
    const std::string python = pybind11::module_::import("sys").attr("executable").cast<std::string>();
    throw pybind11::import_error("idmpc needs numpy, which this interpreter (" + python +
                                 ") cannot import: run it with " IDMPC_PYTHON_EXECUTABLE
                                 ", the interpreter idmpc was built for (numpy from Debian's python3-numpy), "
                                 "or install numpy for this one");
  }
  m.doc() = "idmpc: nonlinear MPC of robot arms (forward- and inverse-dynamics formulations, C/GMRES) "
            "with MuJoCo as plant";
  m.attr("__version__") = IDMPC_VERSION;
  m.attr("mujoco_version") = mj_versionString();
  pybind11::register_exception<idmpc::python::DebugCheckFailed>(m, "DebugCheckError", PyExc_AssertionError);
  idmpc::detail::debug_check_handler = &idmpc::python::raise_debug_check;
  m.def(
      "_fail_debug_check", [] { idmpc::detail::debug_check_failed("false", "a check failed on request", __FILE__, __LINE__); },
      "For tests: what a failed debug check does here (raises DebugCheckError; debug checks themselves are "
      "compiled in debug and sanitizer builds only).");
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
