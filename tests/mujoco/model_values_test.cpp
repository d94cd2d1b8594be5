// Hostile model files: NaN or infinity in any number the controller, the horizon or the torque
// limits use, and includes that form a cycle or name devices, FIFOs or directories. MuJoCo 2.2
// compiles these (its range checks, lower < upper, compare with NaN, which is never true) and at
// most warns; the loader and the importer refuse each with one line naming the file, the element
// and the attribute.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "support/errors.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;
using test::arm2_mjcf;
using test::error_of;

class ModelValues : public ::testing::Test {
 protected:
  void SetUp() override {
    mj::install_error_handlers();
    dir_ = fs::temp_directory_path() / ("idmpc_model_values_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    mj::take_warnings();  // MuJoCo warns about some of the NaN values it compiles
    fs::remove_all(dir_);
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  // the one-line error of loading and importing the model
  std::string import_error(const std::string& xml) const {
    const std::string path = write("model.xml", xml);
    return error_of([&] {
      const mj::ModelPtr m = mj::load_model(path);
      mj::import_model(m.get(), path);
    });
  }
  fs::path dir_;
};

TEST_F(ModelValues, ArmLoadsAsWritten) { EXPECT_EQ(import_error(arm2_mjcf("", "")), "no exception"); }

TEST_F(ModelValues, NonFiniteNumbersInTheFileAreRefusedNamingElementLineAndAttribute) {
  struct Case {
    std::string element, attribute, tag;
    int line;
  };
  // MuJoCo compiles each of these, or (mass="nan") silently takes the density's mass instead
  const std::vector<Case> cases = {
      {"motor0", R"(ctrlrange="nan 1")", "<motor> 'motor0'", 15},
      {"motor0", R"(ctrlrange="-1 inf")", "<motor> 'motor0'", 15},
      {"motor0", R"(forcelimited="true" forcerange="-5 nan")", "<motor> 'motor0'", 15},
      {"motor0", R"(gear="nan")", "<motor> 'motor0'", 15},
      {"motor0", R"(gear="1e999")", "<motor> 'motor0'", 15},
      {"joint0", R"(limited="true" range="nan 1")", "<joint> 'joint0'", 6},
      {"joint0", R"(frictionloss="nan")", "<joint> 'joint0'", 6},
      {"joint0", R"(damping="NaN")", "<joint> 'joint0'", 6},
      {"joint0", R"(armature="inf")", "<joint> 'joint0'", 6},
      {"joint0", R"(stiffness="-Infinity")", "<joint> 'joint0'", 6},
      {"geom0", R"(mass="nan")", "<geom> 'geom0'", 7},
      {"geom0", R"(density="nan")", "<geom> 'geom0'", 7},
      {"inertial1", R"(pos="nan 0 0" mass="1" diaginertia="0.1 0.1 0.1")", "<inertial> '(unnamed)'", 8},
      {"inertial1", R"(pos="0 0 0" mass="nan" diaginertia="0.1 0.1 0.1")", "<inertial> '(unnamed)'", 8},
      {"inertial1", R"(pos="0 0 0" mass="1" diaginertia="nan 0.1 0.1")", "<inertial> '(unnamed)'", 8},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.element + " " + c.attribute);
    const std::string message = import_error(arm2_mjcf(c.element, c.attribute));
    EXPECT_NE(message.find("model '" + (dir_ / "model.xml").string() + "': " + c.tag), std::string::npos) << message;
    EXPECT_NE(message.find(" line " + std::to_string(c.line) + ")"), std::string::npos) << message;
    EXPECT_NE(message.find(": expected finite numbers"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

// a model changed after compiling (or a compiled value MuJoCo computed): the importer checks the
// numbers it uses too
TEST_F(ModelValues, NonFiniteNumbersInTheCompiledModelAreRefusedNamingElementAndField) {
  const std::string path = write("model.xml", arm2_mjcf("", ""));
  const mj::ModelPtr m = mj::load_model(path);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    mjtNum* value;
    std::vector<std::string> needles;
  };
  const std::vector<Case> cases = {
      {&m->actuator_ctrlrange[1], {"actuator 'motor0'", "ctrlrange"}},
      {&m->actuator_forcerange[2], {"actuator 'motor1'", "forcerange"}},
      {&m->actuator_gainprm[0], {"actuator 'motor0'", "gainprm"}},
      {&m->actuator_biasprm[mjNBIAS + 1], {"actuator 'motor1'", "biasprm"}},
      {&m->actuator_gear[1], {"actuator 'motor0'", "gear"}},
      {&m->jnt_range[0], {"joint 'joint0'", "range"}},
      {&m->jnt_stiffness[1], {"joint 'joint1'", "stiffness"}},
      {&m->dof_frictionloss[0], {"joint 'joint0'", "frictionloss"}},
      {&m->dof_damping[1], {"joint 'joint1'", "damping"}},
      {&m->dof_armature[0], {"joint 'joint0'", "armature"}},
      {&m->qpos0[1], {"joint 'joint1'", "reference position"}},
      {&m->body_mass[1], {"body 'link0'", "mass"}},
      {&m->body_ipos[3 * 2], {"body 'link1'", "centre of mass"}},
      {&m->body_iquat[4 * 2], {"body 'link1'", "inertia frame"}},
      {&m->body_inertia[3 * 1 + 2], {"body 'link0'", "inertia"}},
      {&m->opt.timestep, {"timestep"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.needles.back());
    const mjtNum kept = *c.value;
    *c.value = nan;
    const std::string message = error_of([&] { mj::import_model(m.get(), path); });
    *c.value = kept;
    for (const std::string& needle : c.needles) EXPECT_NE(message.find(needle), std::string::npos) << message;
    EXPECT_NE(message.find("non-finite"), std::string::npos) << message;
    EXPECT_NE(message.find(path), std::string::npos) << message;
  }
  EXPECT_EQ(error_of([&] { mj::import_model(m.get(), path); }), "no exception");
}

TEST_F(ModelValues, NonFiniteKeyframeIsRefused) {
  const std::string keyframe = R"(<keyframe><key name="home" qpos="nan 0"/></keyframe>)";
  EXPECT_NE(import_error(arm2_mjcf("", "", keyframe)).find("<key> 'home'"), std::string::npos);
  // in a compiled model: when the task starts from it
  const std::string path = write("key.xml", arm2_mjcf("", "", R"(<keyframe><key name="home" qpos="0 0"/></keyframe>)"));
  const mj::ModelPtr m = mj::load_model(path);
  m->key_qpos[1] = std::numeric_limits<double>::infinity();
  const std::string message = error_of([&] { mj::keyframe_qpos(m.get(), "home", path); });
  EXPECT_NE(message.find("keyframe 'home'"), std::string::npos) << message;
  EXPECT_NE(message.find("qpos (0 inf)"), std::string::npos) << message;
}

TEST_F(ModelValues, IncludeCyclesAndRepeatsAreRefusedAtOnce) {
  std::string includes;
  for (int k = 0; k < 6; ++k) includes += "  <include file=\"self.xml\"/>\n";
  const std::string self = write("self.xml", "<mujoco>\n" + includes + "</mujoco>\n");
  const auto start = std::chrono::steady_clock::now();
  std::string message = error_of([&] { mj::load_model(self); });
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
  EXPECT_EQ(message, "model '" + self + "': <include> 'self.xml' (" + self + " line 2) is an include cycle (" + self +
                         " -> " + (dir_ / "self.xml").string() + ")");
  // a file included twice (not a cycle): MuJoCo includes each file once
  write("part.xml", "<mujoco/>\n");
  const std::string twice =
      write("twice.xml", "<mujoco>\n  <include file=\"part.xml\"/>\n  <include file=\"part.xml\"/>\n</mujoco>\n");
  message = error_of([&] { mj::load_model(twice); });
  EXPECT_NE(message.find("line 3) includes"), std::string::npos) << message;
  EXPECT_NE(message.find("a second time"), std::string::npos) << message;
}

TEST_F(ModelValues, ModelsAndIncludesMustBeRegularFiles) {
  EXPECT_EQ(error_of([&] { mj::load_model(dir_.string()); }),
            "model '" + dir_.string() + "': is a directory, expected an MJCF or URDF file");
  EXPECT_EQ(error_of([&] { mj::load_model("/dev/zero"); }),
            "model '/dev/zero': is a character device, expected an MJCF or URDF file");
  const std::string fifo = (dir_ / "fifo.xml").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(error_of([&] { mj::load_model(fifo); }),
            "model '" + fifo + "': is a FIFO (named pipe), expected an MJCF or URDF file");
  const std::string zero = write("zero.xml", "<mujoco>\n  <include file=\"/dev/zero\"/>\n</mujoco>\n");
  EXPECT_EQ(error_of([&] { mj::load_model(zero); }), "model '" + zero + "': <include> '/dev/zero' (" + zero +
                                                         " line 2): is a character device, expected an MJCF file");
  const std::string missing = write("missing.xml", "<mujoco>\n  <include file=\"absent.xml\"/>\n</mujoco>\n");
  EXPECT_NE(error_of([&] { mj::load_model(missing); }).find("<include> 'absent.xml'"), std::string::npos);
}

}  // namespace
}  // namespace idmpc
