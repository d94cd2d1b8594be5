// Frames of the robot and their kinematics, frame targets and moving references (trajectories).
// Trajectories are immutable and shared (shared_ptr) with the settings and runs that use them.
// Arrays of several samples (waypoints, CSV rows, sample(times)) have one row per time.

#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/experiment/trajectory_io.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/ocp/cost.hpp"

namespace idmpc::python {
namespace {

using Vector = VecX<double>;
using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;
// samples in rows (K × dim), as numpy users and CSV files hold them
using RowSamples = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

Frame load_frame(const std::string& path, const std::string& name) {
  const mj::LoadedModel loaded = mj::load_model_translated(path);
  return mj::import_frame(loaded.model.get(), name, path);
}

std::tuple<Vec3<double>, Mat3<double>, Jacobian> frame_kinematics(const Model& model, const Frame& frame,
                                                                 const Vector& q) {
  check_size("frame_kinematics: q", q.size(), model.n);
  FrameKinematics<double> fk(model, frame);
  fk.compute(model, q);
  Jacobian J(6, model.n);
  fk.jacobian(J);
  return {fk.position(), fk.rotation(), J};
}

using Times = py::array_t<double, py::array::c_style | py::array::forcecast>;

// value and rate at t: (dim,) each for a scalar t, (K, dim) each for K times
py::tuple sample(const Trajectory& trajectory, const Times& t) {
  const int dim = trajectory.dim();
  Vector value(dim), rate(dim);
  if (t.ndim() == 0) {
    trajectory.sample(*t.data(), value, rate);
    return py::make_tuple(value, rate);
  }
  if (t.ndim() != 1) {
    throw std::invalid_argument("sample: t must be a number or a 1-D array of times, got " +
                                std::to_string(t.ndim()) + " dimensions");
  }
  const auto k = static_cast<Eigen::Index>(t.shape(0));
  RowSamples values(k, dim), rates(k, dim);
  for (Eigen::Index i = 0; i < k; ++i) {
    trajectory.sample(t.data()[i], value, rate);
    values.row(i) = value.transpose();
    rates.row(i) = rate.transpose();
  }
  return py::make_tuple(values, rates);
}

std::vector<double> times_of(const std::vector<double>& times, const RowSamples& values, const char* what) {
  if (static_cast<Eigen::Index>(times.size()) != values.rows()) {
    throw std::invalid_argument(std::string(what) + ": values has " + std::to_string(values.rows()) +
                                " rows, expected one per time (" + std::to_string(times.size()) + ")");
  }
  return times;
}

std::shared_ptr<Trajectory> trajectory_from_dict(const py::handle& d, const Vector& start, const std::string& base_dir,
                                                 const std::string& where) {
  nlohmann::json j;
  const std::string text = json_dumps(d, where);
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(where + ": expected JSON, got a parse error: " + e.what());
  }
  return std::shared_ptr<Trajectory>(trajectory_from_json(j, where, start, base_dir));
}

std::string repr(const char* kind, const Trajectory& t) {
  return std::string("<idmpc.") + kind + " " + t.describe() + ">";
}

}  // namespace

void bind_tracking(py::module_& m) {
  py::class_<Frame>(m, "Frame",
                    "A frame rigidly attached to a link of a Model (a MuJoCo site or body): its link and its "
                    "placement on it. From load_frame(path, name) or TaskRun.frame(name).")
      .def(py::init([](std::string name, int link, const Vec3<double>& position, const Mat3<double>& rotation) {
             Frame f;
             f.name = std::move(name);
             f.link = link;
             f.placement.r = position;
             f.placement.E = rotation.transpose();
             return f;
           }),
           py::arg("name"), py::arg("link"), py::arg("position") = Vec3<double>(Vec3<double>::Zero()),
           py::arg("rotation") = Mat3<double>(Mat3<double>::Identity()),
           "A frame on link `link` (-1: the base) at `position` with axes `rotation` (columns), both in the "
           "link's coordinates; checked against a model when used.")
      .def_readwrite("name", &Frame::name, "for messages, e.g. \"site 'tip'\"")
      .def_readwrite("link", &Frame::link, "the link it moves with; -1: fixed to the base")
      .def_property(
          "position", [](const Frame& f) -> Vec3<double> { return f.placement.r; },
          [](Frame& f, const Vec3<double>& p) { f.placement.r = p; }, "its origin in the link's coordinates")
      .def_property(
          "rotation", [](const Frame& f) -> Mat3<double> { return f.placement.E.transpose(); },
          [](Frame& f, const Mat3<double>& R) { f.placement.E = R.transpose(); },
          "link <- frame: its axes in the link's coordinates (columns)")
      .def("__repr__", [](const Frame& f) {
        return "<idmpc.Frame " + f.name + " on link " + std::to_string(f.link) + ">";
      });

  m.def("load_frame", &load_frame, py::arg("path"), py::arg("name"),
        "The Frame of the site called name, or else of the body called name (\"world\": the base), on the "
        "links load_model(path) makes. Raises ValueError naming the model and the frame, with the model's "
        "site names, if there is neither.");
  m.def("frame_kinematics", &frame_kinematics, py::arg("model"), py::arg("frame"), py::arg("q"),
        "(position, rotation, jacobian) of frame at q: its origin in world coordinates (3,), world <- frame "
        "(3 x 3, its axes as columns, MuJoCo's site_xmat) and the world-aligned 6 x n Jacobian, translational "
        "rows first (MuJoCo's [jacp; jacr]). Raises ValueError if the frame does not fit the model.");

  py::class_<FrameTarget>(m, "FrameTarget",
                          "A target pose for a frame with the cost 1/2 (p - p_ref)' diag(w_p) (p - p_ref) + "
                          "w_o (1 - cos theta), theta the angle of R_ref' R (docs/tasks.md). Vector and matrix "
                          "attributes are read-only views: assign a whole array.")
      .def(py::init([](const Frame& frame, const Vec3<double>& position, const Mat3<double>& rotation,
                       const Vec3<double>& position_weight, double orientation_weight) {
             return FrameTarget{frame, position_weight, orientation_weight, position, rotation};
           }),
           py::arg("frame"), py::arg("position") = Vec3<double>(Vec3<double>::Zero()),
           py::arg("rotation") = Mat3<double>(Mat3<double>::Identity()),
           py::arg("position_weight") = Vec3<double>(Vec3<double>::Zero()),
           py::arg("orientation_weight") = 0.0)
      .def_readwrite("frame", &FrameTarget::frame)
      .def_readwrite("position", &FrameTarget::position, "p_ref, world coordinates [m]")
      .def_readwrite("rotation", &FrameTarget::rotation, "R_ref: the target's axes in world coordinates (columns)")
      .def_readwrite("position_weight", &FrameTarget::position_weight, "w_p per world axis [1/m^2]")
      .def_readwrite("orientation_weight", &FrameTarget::orientation_weight, "w_o")
      .def("__repr__", [](const FrameTarget& t) { return "<idmpc.FrameTarget " + t.frame.name + ">"; });

  m.def("rotation_angle", &rotation_angle, py::arg("R"), py::arg("R_ref"),
        "The angle in [0, pi] of R_ref' R: the orientation error the frame cost weighs.");

  py::class_<Trajectory, std::shared_ptr<Trajectory>>(
      m, "Trajectory",
      "A reference that moves (immutable): its value and rate at any time t [s]. Before its start and after "
      "its end it holds its end values with zero rate.")
      .def_property_readonly("dim", &Trajectory::dim)
      .def("sample", &sample, py::arg("t"),
           "(value, rate) at t: arrays (dim,) for a number t, (K, dim) for K times.")
      .def("describe", &Trajectory::describe, "one line saying what it is, as run summaries do")
      .def("__repr__", [](const Trajectory& t) { return repr("Trajectory", t); });

  py::class_<ConstantTrajectory, Trajectory, std::shared_ptr<ConstantTrajectory>>(m, "ConstantTrajectory")
      .def(py::init<Vector>(), py::arg("value"), "A fixed value (finite, at least one entry), rate zero.")
      .def("__repr__", [](const Trajectory& t) { return repr("ConstantTrajectory", t); });

  py::class_<CircleTrajectory, Trajectory, std::shared_ptr<CircleTrajectory>>(
      m, "CircleTrajectory",
      "A circle in 3-D after a smooth start: p(t) = center + radius (cos phi e1 + sin phi e2), e2 = normal x e1, "
      "phi' = 2 pi frequency (3x^2 - 2x^3) for x = t/ramp < 1, 2 pi frequency after; p(0) = center + radius e1.")
      .def(py::init<const Vec3<double>&, const Vec3<double>&, double, double, const Vec3<double>&, double>(),
           py::arg("center"), py::arg("normal"), py::arg("radius"), py::arg("frequency"), py::arg("e1"),
           py::arg("ramp") = 0.0,
           "normal and e1 unit and orthogonal, radius [m] and frequency [Hz] positive, ramp [s] >= 0; "
           "ValueError naming the bad one.")
      .def_property_readonly("center", &CircleTrajectory::center)
      .def_property_readonly("normal", &CircleTrajectory::normal)
      .def_property_readonly("e1", &CircleTrajectory::e1)
      .def_property_readonly("e2", &CircleTrajectory::e2)
      .def_property_readonly("radius", &CircleTrajectory::radius)
      .def_property_readonly("frequency", &CircleTrajectory::frequency)
      .def_property_readonly("ramp", &CircleTrajectory::ramp)
      .def(
          "phase",
          [](const CircleTrajectory& c, double t) {
            double phi = 0, omega = 0;
            c.phase(t, phi, omega);
            return std::make_pair(phi, omega);
          },
          py::arg("t"), "(phi, omega): the phase (in [0, 2 pi) after the ramp) and angular speed at t")
      .def("__repr__", [](const Trajectory& t) { return repr("CircleTrajectory", t); });

  py::class_<WaypointTrajectory, Trajectory, std::shared_ptr<WaypointTrajectory>>(
      m, "WaypointTrajectory",
      "Waypoints at strictly increasing times joined by rest-to-rest minimum-jerk segments (velocity and "
      "acceleration zero at each); a straight line is two waypoints.")
      .def(py::init([](const std::vector<double>& times, const RowSamples& values) {
             return std::make_shared<WaypointTrajectory>(times_of(times, values, "WaypointTrajectory"),
                                                         values.transpose());
           }),
           py::arg("times"), py::arg("values"), "times (K,) [s], values (K, dim): one row per waypoint.")
      .def_property_readonly("times", &WaypointTrajectory::times)
      .def_property_readonly(
          "values", [](const WaypointTrajectory& w) -> RowSamples { return w.values().transpose(); }, "(K, dim)")
      .def("__repr__", [](const Trajectory& t) { return repr("WaypointTrajectory", t); });

  py::class_<SampledTrajectory, Trajectory, std::shared_ptr<SampledTrajectory>>(
      m, "SampledTrajectory",
      "Samples at strictly increasing times (a planner's output) joined by a C1 piecewise-cubic Hermite "
      "interpolant with Catmull-Rom tangents; the rate is its derivative.")
      .def(py::init([](const std::vector<double>& times, const RowSamples& values) {
             return std::make_shared<SampledTrajectory>(times_of(times, values, "SampledTrajectory"),
                                                        values.transpose());
           }),
           py::arg("times"), py::arg("values"), "times (K,) [s], K >= 2, values (K, dim): one row per sample.")
      .def_property_readonly("times", &SampledTrajectory::times)
      .def_property_readonly(
          "values", [](const SampledTrajectory& s) -> RowSamples { return s.values().transpose(); }, "(K, dim)")
      .def_property_readonly(
          "tangents", [](const SampledTrajectory& s) -> RowSamples { return s.tangents().transpose(); },
          "(K, dim): the interpolant's rate at each sample")
      .def("__repr__", [](const Trajectory& t) { return repr("SampledTrajectory", t); });

  m.def(
      "read_trajectory_csv",
      [](const std::string& path, int dim) {
        return std::make_shared<SampledTrajectory>(read_trajectory_csv(path, dim));
      },
      py::arg("path"), py::arg("dim"),
      "A SampledTrajectory from a CSV file: rows of a time [s] then dim values; an optional header, blank "
      "lines and # comments. Raises ValueError naming the file, line and column.");
  m.def("trajectory_from_dict", &trajectory_from_dict, py::arg("d"), py::arg("start"), py::arg("base_dir") = "",
        py::arg("where") = "trajectory dict",
        "A moving reference from a task file's \"reference\" object as a dict ({\"shape\": \"circle\" | "
        "\"line\" | \"waypoints\" | \"csv\", ...}, docs/tasks.md), given its value at t = 0 (start, whose "
        "size is its dim); a \"csv\" file is found relative to base_dir. Raises ValueError naming `where` and "
        "the field.");
}

}  // namespace idmpc::python
