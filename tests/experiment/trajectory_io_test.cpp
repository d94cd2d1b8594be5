// Moving references from data: a planner's CSV (header, comments, and one clear line for each
// malformed case) and the task file's "reference" object (each shape, its defaults, unknown fields
// and wrong dimensions).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "idmpc/experiment/trajectory_io.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("idmpc_trajectory_io_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = path_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  std::string path() const { return path_.string(); }

 private:
  fs::path path_;
};

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

VecX<double> value_at(const Trajectory& traj, double t) {
  VecX<double> v(traj.dim()), r(traj.dim());
  traj.sample(t, v, r);
  return v;
}

VecX<double> rate_at(const Trajectory& traj, double t) {
  VecX<double> v(traj.dim()), r(traj.dim());
  traj.sample(t, v, r);
  return r;
}

// --- CSV ---

TEST(ReadTrajectoryCsv, SkipsHeaderCommentsAndBlankLines) {
  TempDir dir;
  const std::string path = dir.write("plan.csv",
                                     "# from the planner\n"
                                     "time, x, y\n"
                                     "\n"
                                     "0, 0.0, 1.0\r\n"
                                     "  # a comment line\n"
                                     "0.5 ,0.25, 1.5   # halfway\n"
                                     "1.0,1e0,+2\n"
                                     "\t\n");
  const SampledTrajectory traj = read_trajectory_csv(path, 2);
  EXPECT_EQ(traj.times(), (std::vector<double>{0, 0.5, 1}));
  MatX<double> P(2, 3);
  P << 0, 0.25, 1, 1, 1.5, 2;
  EXPECT_EQ(traj.values(), P);
}

TEST(ReadTrajectoryCsv, ReadsAFileWithoutHeader) {
  TempDir dir;
  const SampledTrajectory traj = read_trajectory_csv(dir.write("plan.csv", "0,1\n2,3\n"), 1);
  EXPECT_EQ(traj.times(), (std::vector<double>{0, 2}));
  EXPECT_EQ(traj.values()(0, 1), 3);
  // the rate of a two-sample file is the secant
  EXPECT_DOUBLE_EQ(rate_at(traj, 1)[0], 1);
}

TEST(ReadTrajectoryCsv, SkipsAByteOrderMark) {
  TempDir dir;
  const SampledTrajectory traj = read_trajectory_csv(dir.write("plan.csv", "\xEF\xBB\xBF" "0,1\n2,3\n"), 1);
  EXPECT_EQ(traj.times(), (std::vector<double>{0, 2}));
}

TEST(ReadTrajectoryCsv, ParsesNumbersStrictly) {
  TempDir dir;
  // leading zeros are decimal, not octal
  const SampledTrajectory traj = read_trajectory_csv(dir.write("plan.csv", "0,010\n1,-0.5e-1\n"), 1);
  EXPECT_EQ(traj.values()(0, 0), 10);
  EXPECT_EQ(traj.values()(0, 1), -0.05);
  const std::string path = dir.write("bad.csv", "");
  const auto error = [&](const std::string& text) {
    std::ofstream(path) << text;
    return error_of([&] { read_trajectory_csv(path, 1); });
  };
  const std::string file = "trajectory file '" + path + "'";
  EXPECT_EQ(error("0,1\n1,abc\n"), file + " line 2, column 2: expected a number, got 'abc'");
  EXPECT_EQ(error("0,1\n1,1.5x\n"), file + " line 2, column 2: expected a number, got '1.5x'");
  EXPECT_EQ(error("0,1\n1,0x10\n"), file + " line 2, column 2: expected a number, got '0x10'");
  EXPECT_EQ(error("0,1\n1,\n"), file + " line 2, column 2: expected a number, got ''");
  EXPECT_EQ(error("0,1\n1,1 2\n"), file + " line 2, column 2: expected a number, got '1 2'");
  EXPECT_EQ(error("0,1\n1,+-1\n"), file + " line 2, column 2: expected a number, got '+-1'");
  EXPECT_EQ(error("0,1\n1,inf\n"), file + " line 2, column 2: expected a finite number, got 'inf'");
  EXPECT_EQ(error("0,nan\n1,1\n"), file + " line 1, column 2: expected a finite number, got 'nan'");
  EXPECT_EQ(error("0,1\n1,1e400\n"), file + " line 2, column 2: expected a number in double range, got '1e400'");
  // a header is only a first line; a later line of words is data
  EXPECT_EQ(error("0,1\nt,x\n"), file + " line 2, column 1: expected a number, got 't'");
  // a first line with a number in it is data, not a header
  EXPECT_EQ(error("O,1\n1,2\n2,3\n"), file + " line 1, column 1: expected a number, got 'O'");
}

TEST(ReadTrajectoryCsv, RejectsEachMalformedFileWithOneLine) {
  TempDir dir;
  const std::string path = dir.write("bad.csv", "");
  const auto error = [&](const std::string& text, int dim = 2) {
    std::ofstream(path) << text;
    return error_of([&] { read_trajectory_csv(path, dim); });
  };
  const std::string file = "trajectory file '" + path + "'";
  EXPECT_EQ(error("0,1,2\n1,1\n"), file + " line 2: expected 3 columns (time and 2 values), got 2");
  EXPECT_EQ(error("0,1,2\n1,1,2,3\n"), file + " line 2: expected 3 columns (time and 2 values), got 4");
  EXPECT_EQ(error("0,1,2\n1,1,2,\n"), file + " line 2: expected 3 columns (time and 2 values), got 4");
  // a header has the data's columns too
  EXPECT_EQ(error("t,x\n0,1\n1,2\n", 1), "no exception");
  EXPECT_EQ(error("t,x,y,z\n0,1,2\n1,1,2\n"), file + " line 1: expected 3 columns (time and 2 values), got 4 (header)");
  EXPECT_EQ(error("# c\n0,1,2\n\n0.5,1,2\n0.5,1,2\n"),
            file + " line 5, column 1: expected a time after 0.5 s on line 4 (strictly increasing), got '0.5'");
  EXPECT_EQ(error("0,1,2\n-1,1,2\n"),
            file + " line 2, column 1: expected a time after 0 s on line 1 (strictly increasing), got '-1'");
  EXPECT_EQ(error("0,1,2\n"), file + ": expected at least 2 rows of samples, got 1");
  EXPECT_EQ(error("time,x,y\n# nothing\n"), file + ": expected at least 2 rows of samples, got 0");
  EXPECT_EQ(error(""), file + ": expected at least 2 rows of samples, got 0");
  EXPECT_EQ(error("0,1\n1,2\n", 0), file + ": expected a dimension >= 1, got 0");
}

TEST(ReadTrajectoryCsv, RejectsAnUnreadableFile) {
  TempDir dir;
  const std::string missing = dir.path() + "/missing.csv";
  EXPECT_EQ(error_of([&] { read_trajectory_csv(missing, 1); }), "trajectory file '" + missing + "': does not exist");
  EXPECT_EQ(error_of([&] { read_trajectory_csv(dir.path(), 1); }),
            "trajectory file '" + dir.path() + "': is a directory, expected a CSV file");
}

// --- JSON ---

const std::string kWhere = "task 'a.json' field 'reference'";

std::unique_ptr<Trajectory> from_json(const std::string& text, const VecX<double>& start,
                                      const std::string& base_dir = ".") {
  return trajectory_from_json(json::parse(text), kWhere, start, base_dir);
}

std::string json_error(const std::string& text, const VecX<double>& start, const std::string& base_dir = ".") {
  return error_of([&] { from_json(text, start, base_dir); });
}

const Vec3<double> kStart(0.3, -0.1, 0.5);

const CircleTrajectory& as_circle(const std::unique_ptr<Trajectory>& traj) {
  const auto* circle = dynamic_cast<const CircleTrajectory*>(traj.get());
  if (!circle) throw std::logic_error("not a circle: " + traj->describe());
  return *circle;
}

TEST(TrajectoryFromJson, CircleDefaultsPassThroughTheStart) {
  const auto traj = from_json(R"({"shape": "circle", "radius": 0.05, "frequency": 0.5})", kStart);
  const CircleTrajectory& circle = as_circle(traj);
  // normal +x, e1 = +z (world +z in the plane), ramp 1 s, centre = start − r·e1
  EXPECT_EQ(circle.normal(), Vec3<double>::UnitX());
  EXPECT_EQ(circle.e1(), Vec3<double>::UnitZ());
  EXPECT_EQ(circle.ramp(), 1.0);
  EXPECT_EQ(circle.radius(), 0.05);
  EXPECT_EQ(circle.frequency(), 0.5);
  EXPECT_LT((circle.center() - (kStart - 0.05 * Vec3<double>::UnitZ())).norm(), 1e-16);
  EXPECT_LT((value_at(circle, 0) - kStart).norm(), 1e-16);
}

TEST(TrajectoryFromJson, CircleStartDirectionIsWorldZInThePlane) {
  // a tilted normal (not unit as written): e1 is +z projected onto the plane
  const auto tilted = from_json(R"({"shape": "circle", "radius": 0.1, "frequency": 1, "normal": [0, 2, 2], "ramp": 0})",
                                kStart);
  const Vec3<double> n = Vec3<double>(0, 1, 1).normalized();
  EXPECT_LT((as_circle(tilted).normal() - n).norm(), 1e-15);
  EXPECT_LT((as_circle(tilted).e1() - Vec3<double>(0, -1, 1).normalized()).norm(), 1e-15);
  EXPECT_EQ(as_circle(tilted).ramp(), 0);
  EXPECT_LT((value_at(*tilted, 0) - kStart).norm(), 1e-15);
  // a normal along z: e1 is +y
  const auto flat = from_json(R"({"shape": "circle", "radius": 0.1, "frequency": 1, "normal": [0, 0, -1]})", kStart);
  EXPECT_EQ(as_circle(flat).e1(), Vec3<double>::UnitY());
  EXPECT_LT((value_at(*flat, 0) - kStart).norm(), 1e-15);
  // a normal all but along z: e1 from the short projection of +z, still perpendicular to it
  for (const char* normal : {"[1e-9, 0, 1]", "[2e-9, 1e-9, -1]", "[1e-7, 0, 1]"}) {
    const auto steep = from_json(std::string(R"({"shape": "circle", "radius": 0.1, "frequency": 1, "normal": )") +
                                     normal + "}",
                                 kStart);
    EXPECT_LT(std::abs(as_circle(steep).e1().dot(as_circle(steep).normal())), 1e-15) << normal;
    EXPECT_LT((value_at(*steep, 0) - kStart).norm(), 1e-15) << normal;
  }
}

TEST(TrajectoryFromJson, AFacingCircleIsAVerticalPlaneFacingTheWorldOrigin) {
  // start (0.3, -0.4, 0.5): the normal is its horizontal direction (0.6, -0.8, 0), e1 world +z
  const VecX<double> start = Vec3<double>(0.3, -0.4, 0.5);
  const auto traj = from_json(R"({"shape": "circle", "radius": 0.05, "frequency": 0.5, "normal": "facing"})", start);
  EXPECT_LT((as_circle(traj).normal() - Vec3<double>(0.6, -0.8, 0)).norm(), 1e-15);
  EXPECT_EQ(as_circle(traj).e1(), Vec3<double>::UnitZ());
  EXPECT_LT((value_at(*traj, 0) - start).norm(), 1e-15);
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 1, "frequency": 1, "normal": "facing"})",
                       Vec3<double>(0, 0, 1)),
            kWhere + ": field 'normal': expected [x, y, z], or \"facing\" with a start off the world's vertical axis, "
                     "got \"facing\"");
}

TEST(TrajectoryFromJson, CircleWithACentreStartsTowardsTheStart) {
  // start projected onto the plane x = const lies along (0, 3, 4) from the centre
  const auto traj = from_json(R"({"shape": "circle", "radius": 0.05, "frequency": 0.5, "center": [0.1, -0.4, 0.1]})",
                              kStart);
  EXPECT_EQ(as_circle(traj).center(), Vec3<double>(0.1, -0.4, 0.1));
  EXPECT_LT((as_circle(traj).e1() - Vec3<double>(0, 0.6, 0.8)).norm(), 1e-15);
  // a start that projects onto the centre: the default e1
  const auto on_axis = from_json(R"({"shape": "circle", "radius": 0.05, "frequency": 0.5, "center": [0, -0.1, 0.5]})",
                                 kStart);
  EXPECT_EQ(as_circle(on_axis).e1(), Vec3<double>::UnitZ());
}

TEST(TrajectoryFromJson, CircleNeedsAPosition) {
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 0.05, "frequency": 0.5})", VecX<double>::Zero(7)),
            kWhere + ": field 'shape': \"circle\" needs a 3-D reference (a position), got dim 7");
  EXPECT_EQ(json_error(R"({"shape": "circle", "frequency": 0.5})", kStart),
            kWhere + ": missing field 'radius' (a positive number [m])");
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": -1, "frequency": 0.5})", kStart),
            kWhere + ": field 'radius': expected a positive number [m], got -1");
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 1, "frequency": "fast"})", kStart),
            kWhere + ": field 'frequency': expected a positive number [Hz] of at most 1e+06, got \"fast\"");
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 1, "frequency": 1, "normal": [0, 0, 0]})", kStart),
            kWhere + ": field 'normal': expected a non-zero list of 3 numbers (the plane's normal), got [0,0,0]");
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 1, "frequency": 1, "center": [0, 0]})", kStart),
            kWhere + ": field 'center': expected a list of 3 numbers (x, y, z [m]), got [0,0]");
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 1, "frequency": 1, "ramp": -0.5})", kStart),
            kWhere + ": field 'ramp': expected a non-negative number [s] of at most 1e+09, got -0.5");
}

TEST(TrajectoryFromJson, LineRunsFromTheStartAfterItsDelay) {
  const VecX<double> start = VecX<double>::LinSpaced(7, 0, 0.6);
  const VecX<double> to = VecX<double>::Constant(7, 1);
  const auto traj = from_json(R"({"shape": "line", "to": [1, 1, 1, 1, 1, 1, 1], "duration": 2, "delay": 0.5})", start);
  EXPECT_EQ(traj->dim(), 7);
  EXPECT_EQ(value_at(*traj, 0), start);
  EXPECT_EQ(value_at(*traj, 0.5), start);
  EXPECT_LT((value_at(*traj, 1.5) - 0.5 * (start + to)).norm(), 1e-15);
  EXPECT_EQ(value_at(*traj, 2.5), to);
  EXPECT_EQ(rate_at(*traj, 2.5).norm(), 0);
  // no delay by default
  const auto now = from_json(R"({"shape": "line", "to": [1, 1, 1, 1, 1, 1, 1], "duration": 2})", start);
  EXPECT_LT((value_at(*now, 1) - 0.5 * (start + to)).norm(), 1e-15);
}

TEST(TrajectoryFromJson, LineNeedsATargetOfItsDim) {
  EXPECT_EQ(json_error(R"({"shape": "line", "to": [1, 2], "duration": 2})", kStart),
            kWhere + ": field 'to': expected a list of 3 numbers (the reference's dim), got [1,2]");
  EXPECT_EQ(json_error(R"({"shape": "line", "to": [1, 2, 3], "duration": 0})", kStart),
            kWhere + ": field 'duration': expected a positive number [s], got 0");
  EXPECT_EQ(json_error(R"({"shape": "line", "to": [1, 2, 3]})", kStart),
            kWhere + ": missing field 'duration' (a positive number [s])");
}

TEST(TrajectoryFromJson, WaypointsStartFromTheStart) {
  const auto traj = from_json(R"({"shape": "waypoints", "points": [{"t": 1, "value": [1, 2]}, {"t": 3, "value": [0, 0]}]})",
                              Eigen::Vector2d(5, 6));
  const auto& w = dynamic_cast<const WaypointTrajectory&>(*traj);
  EXPECT_EQ(w.times(), (std::vector<double>{0, 1, 3}));
  EXPECT_EQ(value_at(w, 0), Eigen::Vector2d(5, 6));
  EXPECT_EQ(value_at(w, 1), Eigen::Vector2d(1, 2));
  EXPECT_EQ(value_at(w, 4), Eigen::Vector2d(0, 0));
  // a first point at t = 0 replaces the start
  const auto at_zero = from_json(R"({"shape": "waypoints", "points": [{"t": 0, "value": [1, 2]}]})",
                                 Eigen::Vector2d(5, 6));
  EXPECT_EQ(dynamic_cast<const WaypointTrajectory&>(*at_zero).times(), (std::vector<double>{0}));
  EXPECT_EQ(value_at(*at_zero, 2), Eigen::Vector2d(1, 2));
}

TEST(TrajectoryFromJson, WaypointsNameTheBadPoint) {
  const VecX<double> start = Eigen::Vector2d(5, 6);
  EXPECT_EQ(json_error(R"({"shape": "waypoints", "points": [{"t": 1, "value": [1, 2]}, {"t": 1, "value": [0, 0]}]})", start),
            kWhere + ", 'points'[1]: field 't': expected a time after the previous point's 1 s (strictly increasing), got 1");
  EXPECT_EQ(json_error(R"({"shape": "waypoints", "points": [{"t": 1, "value": [1, 2, 3]}]})", start),
            kWhere + ", 'points'[0]: field 'value': expected a list of 2 numbers (the reference's dim), got [1,2,3]");
  EXPECT_EQ(json_error(R"({"shape": "waypoints", "points": [{"t": 1, "value": [1, 2], "v": 0}]})", start),
            kWhere + ", 'points'[0]: unknown field 'v' for shape \"waypoints\" (expected t, value)");
  EXPECT_EQ(json_error(R"({"shape": "waypoints", "points": [{"t": -1, "value": [1, 2]}]})", start),
            kWhere + ", 'points'[0]: field 't': expected a non-negative number [s], got -1");
  EXPECT_EQ(json_error(R"({"shape": "waypoints", "points": []})", start),
            kWhere + ": field 'points': expected a non-empty list of {\"t\": seconds, \"value\": [...]}, got []");
  EXPECT_EQ(json_error(R"({"shape": "waypoints", "points": [3]})", start),
            kWhere + ", 'points'[0]: expected {\"t\": seconds, \"value\": [...]}, got 3");
}

TEST(TrajectoryFromJson, CsvIsReadRelativeToTheBaseDirectory) {
  TempDir dir;
  dir.write("plan.csv", "t,x,y,z\n0,0.3,-0.1,0.5\n1,0.4,-0.1,0.5\n2,0.4,0,0.5\n");
  const auto traj = from_json(R"({"shape": "csv", "file": "plan.csv"})", kStart, dir.path());
  EXPECT_EQ(dynamic_cast<const SampledTrajectory&>(*traj).times(), (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(value_at(*traj, 2), Vec3<double>(0.4, 0, 0.5));
  // the file's own error, after where and the field
  const std::string path = (fs::path(dir.path()) / "plan.csv").string();
  EXPECT_EQ(json_error(R"({"shape": "csv", "file": "plan.csv"})", Eigen::Vector2d(0, 0), dir.path()),
            kWhere + ": field 'file': trajectory file '" + path + "' line 1: expected 3 columns (time and 2 values), got 4 (header)");
  EXPECT_EQ(json_error(R"({"shape": "csv"})", kStart),
            kWhere + ": missing field 'file' (a CSV file name, relative to the task file)");
}

TEST(TrajectoryFromJson, RejectsUnknownFieldsAndShapes) {
  EXPECT_EQ(json_error(R"({"shape": "line", "to": [1, 2, 3], "duration": 1, "speed": 2})", kStart),
            kWhere + ": unknown field 'speed' for shape \"line\" (expected delay, duration, shape, to)");
  EXPECT_EQ(json_error(R"({"shape": "circle", "radius": 1, "frequency": 1, "centre": [0, 0, 0]})", kStart),
            kWhere + ": unknown field 'centre' for shape \"circle\" (expected center, frequency, normal, radius, ramp, shape)");
  EXPECT_EQ(json_error(R"({"shape": "spiral"})", kStart),
            kWhere + ": field 'shape': expected \"circle\", \"line\", \"waypoints\" or \"csv\", got \"spiral\"");
  EXPECT_EQ(json_error(R"({"radius": 1})", kStart),
            kWhere + ": missing field 'shape' (\"circle\", \"line\", \"waypoints\" or \"csv\")");
  EXPECT_EQ(json_error(R"("circle")", kStart),
            kWhere + ": expected an object {\"shape\": \"circle\" | \"line\" | \"waypoints\" | \"csv\", ...}, got \"circle\"");
  EXPECT_EQ(json_error(R"({"shape": "line", "to": [], "duration": 1})", VecX<double>()),
            kWhere + ": the reference's start value is empty (dim 0)");
}

}  // namespace
}  // namespace idmpc
