// Values that are in range for their type but make no run: a task's frame target with vectors
// of the wrong size or a frame name that is empty or holds a NUL byte, moving references whose
// samples would overflow to NaN (a circle at 1e308 Hz or with a 1e308 s ramp, samples 1e-310 s
// apart). Each is refused with one line naming the field (and the file), before anything runs.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/experiment/run_record.hpp"
#include "idmpc/experiment/task.hpp"
#include "idmpc/experiment/trajectory_io.hpp"
#include "idmpc/ocp/trajectory.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

// the message of the std::invalid_argument `f` throws, or "" (then the test fails)
template <class F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "nothing was refused";
  return "";
}

void expect_names(const std::string& message, std::initializer_list<const char*> needles) {
  for (const char* needle : needles) EXPECT_NE(message.find(needle), std::string::npos) << "no '" << needle << "' in: " << message;
}

// a task on a 2-joint arm with a frame target, resolvable as written
Task target_task(const FrameTask& target) {
  Task t = arm_defaults();
  t.q0_rule.clear();
  t.q0 = {0, 0};
  t.qref = {0};
  t.target = target;
  return t;
}

TEST(TaskTarget, VectorsOfTheWrongSizeAreRefusedNamingTheField) {
  EXPECT_NO_THROW(resolve(target_task(FrameTask{"tip", {}, {}, {1e4}, 100}), 2));
  EXPECT_NO_THROW(resolve(target_task(FrameTask{"tip", {0.1, 0.2, 0.3}, {1, 0, 0, 0}, {1, 2, 3}, 100}), 2));
  // an empty weight vector (FrameTask(position_weight=[]) from Python) read a value that is not there
  expect_names(refusal([] { resolve(target_task(FrameTask{"tip", {}, {}, {}, 100}), 2); }),
               {"target.weights.position", "0 values", "1 or 3"});
  expect_names(refusal([] { resolve(target_task(FrameTask{"tip", {}, {}, {1, 2}, 100}), 2); }),
               {"target.weights.position", "2 values"});
  expect_names(refusal([] { resolve(target_task(FrameTask{"tip", {0.1, 0.2}, {}, {1e4}, 100}), 2); }),
               {"target.position", "2 values", "3"});
  expect_names(refusal([] { resolve(target_task(FrameTask{"tip", {}, {1, 0, 0}, {1e4}, 100}), 2); }),
               {"target.orientation", "3 values", "4"});
  expect_names(refusal([] { resolve(target_task(FrameTask{"tip", {0, NAN, 0}, {}, {1e4}, 100}), 2); }),
               {"target.position", "finite"});
}

TEST(TaskTarget, AnEmptyFrameNameOrOneWithANulByteIsRefused) {
  expect_names(refusal([] { resolve(target_task(FrameTask{"", {}, {}, {1e4}, 100}), 2); }),
               {"target.frame", "empty"});
  expect_names(refusal([] { resolve(target_task(FrameTask{std::string("tip\0x", 5), {}, {}, {1e4}, 100}), 2); }),
               {"target.frame", "NUL"});
}

TEST(CircleTrajectory, AFrequencyRampOrSpeedThatOverflowsIsRefused) {
  const Vec3<double> c = Vec3<double>::Zero(), n = Vec3<double>::UnitX(), e1 = Vec3<double>::UnitZ();
  EXPECT_NO_THROW(CircleTrajectory(c, n, 0.05, CircleTrajectory::kMaxFrequency, e1, CircleTrajectory::kMaxRamp));
  expect_names(refusal([&] { CircleTrajectory(c, n, 0.05, 1e308, e1, 1.0); }), {"circle", "frequency", "1e+308"});
  expect_names(refusal([&] { CircleTrajectory(c, n, 0.05, 0.5, e1, 1e308); }), {"circle", "ramp", "1e+308"});
  expect_names(refusal([&] { CircleTrajectory(c, n, 1e303, 1e6, e1, 0.0); }), {"circle", "speed", "radius"});
}

TEST(CircleTrajectory, InRangeEverySampleIsFinite) {
  const CircleTrajectory circle(Vec3<double>::Zero(), Vec3<double>::UnitX(), 0.05, CircleTrajectory::kMaxFrequency,
                                Vec3<double>::UnitZ(), CircleTrajectory::kMaxRamp);
  VecX<double> value(3), rate(3);
  for (const double t : {0.0, 1e-3, 1.0, 1e9, 2e9, 1e15}) {
    circle.sample(t, value, rate);
    EXPECT_TRUE(value.allFinite() && rate.allFinite()) << "t = " << t;
  }
}

TEST(SampledTrajectory, TimesTooCloseForAFiniteRateAreRefused) {
  MatX<double> P(1, 2);
  P << 0.0, 1.0;
  expect_names(refusal([&] { SampledTrajectory({0.0, 1e-310}, P); }), {"sampled trajectory", "t[0]", "t[1]", "overflows"});
  expect_names(refusal([&] { WaypointTrajectory({0.0, 1e-310}, P); }), {"waypoints", "overflows"});
  P << -1e300, 1e300;
  expect_names(refusal([&] { SampledTrajectory({0.0, 1e-10}, P); }), {"overflows"});
}

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("idmpc_hostile_values_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream((path_ / name).string()) << text;
    return (path_ / name).string();
  }
  std::string path() const { return path_.string(); }

 private:
  fs::path path_;
};

// the task file's reference: the refusal names the task file and the field, the CSV file and line
TEST(TrajectoryFromJson, ReferencesThatWouldSampleNaNAreRefusedNamingTheField) {
  const std::string where = "task file 'reach.json', 'reference'";
  const VecX<double> start = Vec3<double>(0.4, 0.1, 0.5);
  auto circle = [&](const nlohmann::json& extra) {
    nlohmann::json j = {{"shape", "circle"}, {"radius", 0.05}, {"frequency", 0.5}};
    j.update(extra);
    return refusal([&] { trajectory_from_json(j, where, start, ""); });
  };
  expect_names(circle({{"frequency", 1e308}}), {"reach.json", "'frequency'", "1e+308"});
  expect_names(circle({{"ramp", 1e308}}), {"reach.json", "'ramp'", "1e+308"});
  expect_names(circle({{"radius", 1e303}, {"frequency", 1e6}}), {"reach.json", "'radius'"});

  const nlohmann::json line = {{"shape", "line"}, {"to", {0.4, 0.1, 0.6}}, {"duration", 1e-310}};
  expect_names(refusal([&] { trajectory_from_json(line, where, start, ""); }), {"reach.json", "'duration'", "overflows"});

  TempDir dir;
  dir.write("plan.csv", "t,x,y,z\n0,0.4,0.1,0.5\n1e-310,0.4,0.1,0.6\n1,0.4,0.1,0.5\n");
  const nlohmann::json csv = {{"shape", "csv"}, {"file", "plan.csv"}};
  expect_names(refusal([&] { trajectory_from_json(csv, where, start, dir.path()); }),
               {"reach.json", "'file'", "plan.csv", "line 3", "1e-310"});
}

// a run summary (render reads the one beside a log) with a field missing or of another type: the
// error names the file and the field and says what was expected, not the JSON library's text
TEST(RunSummary, AMistypedFieldIsNamedWithWhatWasExpected) {
  RunSummary s;
  s.task = arm_defaults();
  s.task.qref = {0.5, 0};
  s.n = 2;
  s.torque_lower = {-1, -1};
  s.torque_upper = {1, 1};
  s.saturated_steps = {0, 0};
  const nlohmann::json good = to_json(s);
  ASSERT_NO_THROW(summary_from_json(good, "run.json"));
  auto message = [&](const std::function<void(nlohmann::json&)>& change) -> std::string {
    nlohmann::json j = good;
    change(j);
    try {
      summary_from_json(j, "run.json");
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    ADD_FAILURE() << "accepted: " << j.dump().substr(0, 200);
    return "";
  };
  const std::string n = message([](nlohmann::json& j) { j["n"] = "two"; });
  expect_names(n, {"run summary 'run.json'", "field 'n'", "an integer", "\"two\""});
  EXPECT_EQ(n.find("json.exception"), std::string::npos) << n;
  expect_names(message([](nlohmann::json& j) { j["latency"]["updates"] = 1.5; }),
               {"'latency.updates'", "an integer", "1.5"});
  expect_names(message([](nlohmann::json& j) { j["phase_ms"] = 3; }), {"'phase_ms'", "an object"});
  expect_names(message([](nlohmann::json& j) { j.erase("warnings"); }), {"missing field 'warnings'"});
  expect_names(message([](nlohmann::json& j) { j["torque_lower"] = {1, "x"}; }),
               {"'torque_lower'", "a list of numbers or nulls"});
  expect_names(message([](nlohmann::json& j) { j["diverged"] = true; }), {"'diverged_at'"});
}

}  // namespace
}  // namespace idmpc
