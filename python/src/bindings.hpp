#pragma once
/// @file bindings.hpp
/// @brief The parts of the Python module idmpc, one function per C++ layer they bind.

#include <stdexcept>
#include <string>

#include <pybind11/pybind11.h>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc::python {

namespace py = pybind11;

/// Model, load_model and the dynamics kernels (rnea, aba, crba and their derivatives)
void bind_model(py::module_& m);
/// Frame, load_frame, frame_kinematics, FrameTarget, rotation_angle, the trajectories
void bind_tracking(py::module_& m);
/// Task, FrameTask, load_task, paper_task, arm_defaults, task_from_dict
void bind_task(py::module_& m);
/// ControllerSettings, Controller, Plant, TaskRun, run_task
void bind_control(py::module_& m);

/// @brief Throws std::invalid_argument (ValueError) unless the vector `name` has n entries:
/// "<name> has <size> entries, expected n = <n>".
void check_size(const char* name, Eigen::Index size, int n);

/// @brief A JSON text as a Python object, through Python's json module (exact: both sides
/// read and write the same text).
py::object json_loads(const std::string& text);
/// @brief A Python object (dict, list, numbers, strings; numpy arrays and scalars as their
/// tolist()) as JSON text. A non-finite float throws std::invalid_argument (ValueError) "<where>:
/// field '<place>': expected a finite number, got nan".
std::string json_dumps(const py::handle& obj, const std::string& where);

/// @brief What a failed debug check throws in the module: idmpc.DebugCheckError (an
/// AssertionError) in Python.
struct DebugCheckFailed : std::logic_error {
  using std::logic_error::logic_error;
};

}  // namespace idmpc::python
