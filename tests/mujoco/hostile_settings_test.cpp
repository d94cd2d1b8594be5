// Settings that name something the run cannot use: a frame target on the world body or on a body
// welded to it (no joint moves it: it would count as reached whatever the controller did), a
// frame name that is empty or holds a NUL byte (MuJoCo would resolve it to another frame), a
// very long frame name (echoed cut), and a horizon N far beyond any use (sized before checked).
// Each throws std::invalid_argument with one line naming it; none crashes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <climits>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/task_run.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

// a one-joint arm on a base welded to the world: sites on the world, on the base and on the link,
// and a site without a name on the world
const char* kArm = R"(<mujoco model="welded">
  <option timestep="0.001"/>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <site name="world_site" pos="0 0 0.1"/>
    <site pos="0 0 0.2"/>
    <body name="base" pos="0 0 0.5">
      <geom type="box" size="0.1 0.1 0.1" mass="5"/>
      <site name="base_site" pos="0 0 0.1"/>
      <body name="link" pos="0 0 0.1">
        <joint name="joint" type="hinge" axis="0 1 0"/>
        <geom type="box" pos="0 0 0.25" size="0.05 0.05 0.25" mass="1"/>
        <site name="tip" pos="0 0 0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="joint" ctrllimited="true" ctrlrange="-20 20"/></actuator>
</mujoco>
)";

class HostileSettings : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("idmpc_hostile_settings_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    model_ = (dir_ / "welded.xml").string();
    std::ofstream(model_) << kArm;
  }
  void TearDown() override { fs::remove_all(dir_); }

  Task task(const std::string& frame) const {
    Task t = task_from_json({{"model", model_}, {"q0", {0.3}}, {"qref", "q0"}, {"duration", 0.01},
                             {"target", {{"frame", frame}}}},
                            "task file 'welded.json'", arm_defaults());
    t.source = (dir_ / "welded.json").string();
    return t;
  }

  // the message of the std::invalid_argument that building the task's run throws
  std::string refusal(const Task& t) const {
    try {
      mj::TaskRun run(t);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    ADD_FAILURE() << "the task was not refused";
    return "";
  }

  fs::path dir_;
  std::string model_;
};

TEST_F(HostileSettings, ATargetFixedToTheWorldIsRefused) {
  EXPECT_NO_THROW(mj::TaskRun(task("tip")));
  for (const char* frame : {"world", "world_site", "base", "base_site"}) {
    const std::string message = refusal(task(frame));
    EXPECT_NE(message.find(std::string("'") + frame + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("fixed to the world"), std::string::npos) << message;
    EXPECT_NE(message.find("welded.json"), std::string::npos) << message;
  }
}

TEST_F(HostileSettings, AnEmptyFrameNameOrOneWithANulByteNamesNoFrame) {
  const mj::LoadedModel loaded = mj::load_model_translated(model_);
  // MuJoCo's own lookup: "" finds the unnamed site, "tip\0…" finds tip
  auto refused = [&](const std::string& name) -> std::string {
    try {
      mj::import_frame(loaded.model.get(), name, model_);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    ADD_FAILURE() << "'" << name << "' named a frame";
    return "";
  };
  EXPECT_NE(refused("").find("empty name"), std::string::npos);
  EXPECT_NE(refused(std::string("tip\0base", 8)).find("NUL byte"), std::string::npos);
  EXPECT_EQ(mj::import_frame(loaded.model.get(), "tip", model_).name, "site 'tip'");
  // through a task too: the task's target is checked before the model is asked
  EXPECT_NE(refusal(task("")).find("target.frame"), std::string::npos);
  EXPECT_NE(refusal(task(std::string("tip\0base", 8))).find("NUL byte"), std::string::npos);
}

TEST_F(HostileSettings, AVeryLongFrameNameIsEchoedCut) {
  const std::string message = refusal(task(std::string(100000, 'x')));
  EXPECT_LT(message.size(), 400u) << message.substr(0, 400);
  EXPECT_NE(message.find("\xE2\x80\xA6 (100000 characters)"), std::string::npos) << message.substr(0, 400);
}

// N is checked before anything is sized from it: 2^31 - 1 stages crashed the constructor
TEST_F(HostileSettings, AControllerHorizonBeyondItsLimitIsRefused) {
  auto model = std::make_shared<const Model>(test::load_problem(model_).model);
  ControllerSettings s;
  s.weights = test::paper_weights(1);
  s.q_ref = VecX<double>::Zero(1);
  for (const int N : {0, -1, kMaxHorizonStages + 1, INT_MAX}) {
    s.N = N;
    try {
      Controller c(model, s);
      ADD_FAILURE() << "N = " << N << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("N must be from 1 to 10000"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(std::to_string(N)), std::string::npos) << e.what();
    }
  }
  s.N = 20;
  EXPECT_NO_THROW(Controller(model, s));
}

}  // namespace
}  // namespace idmpc
