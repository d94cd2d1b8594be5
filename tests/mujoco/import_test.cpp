// The MuJoCo boundary: loader and importer errors name what is wrong, the unmodeled report,
// option flags (gravity, passive), welded-body merging, several joints in one body, and the
// plant's torque → ctrl scaling.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <random>
#include <stdexcept>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/mjcf_scan.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/mujoco/reference.hpp"
#include "support/problems.hpp"
#include "support/random_model.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

// ID/FD against MuJoCo: the same arithmetic up to rounding (as CheckTolerances::mujoco)
constexpr double kMujoco = 1e-10;
// (v₁ − v₀)/Δt vs qacc: Euler's v₁ = v₀ + Δt·qacc rounded, error ≈ ε·|v₀|/Δt ≈ 1e-12
constexpr double kPlantAcceleration = 1e-10;
// summed body masses: a handful of additions of O(1) numbers
constexpr double kMassSum = 1e-12;

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

/// runs `call`, expects exception E whose message contains every one of `parts`
template <typename E>
void expect_throw_naming(const std::function<void()>& call,
                         std::initializer_list<std::string> parts) {
  try {
    call();
    ADD_FAILURE() << "expected an exception naming:" << joined(std::vector<std::string>(parts));
  } catch (const E& e) {
    const std::string what = e.what();
    for (const std::string& p : parts) {
      EXPECT_NE(what.find(p), std::string::npos) << "message lacks '" << p << "': " << what;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

VecX<double> random_vector(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  VecX<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng);
  return x;
}

mj::ImportOptions direct_torques() {
  mj::ImportOptions options;
  options.direct_torque = true;
  return options;
}

double rel(const VecX<double>& x, const VecX<double>& y) {
  return mj::relative_error(x, y);
}

/// a MuJoCo warning anywhere in a test fails it
class ImportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    mj::install_error_handlers();
    const std::vector<std::string> stale = mj::take_warnings();
    ASSERT_TRUE(stale.empty()) << "MuJoCo warnings before the test:" << joined(stale);
  }
  void TearDown() override {
    const std::vector<std::string> warnings = mj::take_warnings();
    EXPECT_TRUE(warnings.empty()) << "MuJoCo warnings:" << joined(warnings);
  }

  /// every check_model comparison passes at a few states
  static void expect_check_model_ok(const mjModel* m, const Model& model, const std::string& label) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      for (const mj::CheckEntry& e : mj::check_model(m, model, 3, seed)) {
        EXPECT_TRUE(e.ok()) << label << " seed " << seed << ": " << e.quantity << " worst "
                            << e.worst << " > tolerance " << e.tolerance;
      }
    }
  }
};

// a three-link chain (hinge, slide, hinge) with masses on every link; `option`, `actuators`
// and attributes for every joint are spliced in
std::string chain_mjcf(const std::string& option, const std::string& actuators,
                       const std::string& joint_attributes = "") {
  return R"(<mujoco model="chain3">
  <option timestep="0.001">)" + option + R"(</option>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="link0" pos="0 0 1">
      <joint name="j0" type="hinge" axis="0 1 0" )" + joint_attributes + R"(/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04" mass="1"/>
      <body name="link1" pos="0.4 0 0" euler="0.2 0.1 0">
        <joint name="j1" type="slide" axis="1 0.3 0.1" )" + joint_attributes + R"(/>
        <geom type="box" pos="0.1 0 0" size="0.1 0.05 0.05" mass="0.7"/>
        <body name="link2" pos="0.2 0 0">
          <joint name="j2" type="hinge" pos="0.01 0 0" axis="0.3 0.2 1" )" + joint_attributes + R"(/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.03" mass="0.5"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>)" + actuators + R"(</actuator>
</mujoco>
)";
}

// ---------------------------------------------------------------------------------------------
// loader errors

TEST_F(ImportTest, MissingFileThrowsNamingThePath) {
  const std::string path = "/nonexistent/idmpc/no_such_model.xml";
  expect_throw_naming<std::runtime_error>([&] { mj::load_model(path); }, {path});
}

TEST_F(ImportTest, MalformedXmlThrowsNamingTheFile) {
  const std::string path = ::testing::TempDir() + "idmpc_import_test_malformed.xml";
  {
    std::ofstream out(path);
    out << "<mujoco><worldbody><body name=\"b\"><geom size=\"0.1\"/></worldbody></mujoco>\n";
  }
  expect_throw_naming<std::runtime_error>([&] { mj::load_model(path); }, {path});
  std::remove(path.c_str());
  // text that is XML but not MJCF fails as well
  expect_throw_naming<std::runtime_error>(
      [] { mj::load_model_from_string("<mujoco><worldbody><body><joint type=\"bogus\"/></body></worldbody></mujoco>"); },
      {"cannot load model"});
}

// ---------------------------------------------------------------------------------------------
// importer errors

TEST_F(ImportTest, BallJointIsRejectedNamingJointAndBody) {
  const mj::ModelPtr m = mj::load_model_from_string(R"(<mujoco>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="hinge0" type="hinge" axis="0 1 0"/>
      <geom type="sphere" size="0.1" mass="1"/>
      <body name="forearm" pos="0.3 0 0">
        <joint name="shoulder_ball" type="ball"/>
        <geom type="sphere" size="0.1" mass="1"/>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  expect_throw_naming<std::invalid_argument>(
      [&] { mj::import_model(m.get(), "ball.xml"); },
      {"shoulder_ball", "forearm", "ball", "ball.xml"});
}

TEST_F(ImportTest, FreeJointIsRejectedNamingJointAndBody) {
  const mj::ModelPtr m = mj::load_model_from_string(R"(<mujoco>
  <worldbody>
    <body name="floating_base" pos="0 0 1">
      <joint name="float" type="free"/>
      <geom type="sphere" size="0.1" mass="1"/>
    </body>
  </worldbody>
</mujoco>)");
  expect_throw_naming<std::invalid_argument>([&] { mj::import_model(m.get(), "free.xml"); },
                                             {"float", "floating_base", "free", "free.xml"});
}

// a joint without a motor is passive: the model is under-actuated, the plant leaves the joint alone
TEST_F(ImportTest, UnderActuatedModelMarksTheBareJointPassive) {
  const mj::ModelPtr m = mj::load_model_from_string(
      chain_mjcf("", R"(<motor name="m0" joint="j0"/><motor name="m2" joint="j2"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "under.xml");
  EXPECT_FALSE(imported.actuation.direct);
  EXPECT_EQ(imported.model.unactuated_joints, std::vector<int>{1});
  EXPECT_EQ(imported.model.actuated_joints, (std::vector<int>{0, 2}));
  EXPECT_EQ(imported.actuation.passive_dofs, std::vector<int>{1});
  EXPECT_EQ(imported.actuation.actuator_of_dof, (std::vector<int>{0, -1, 1}));
  ASSERT_EQ(imported.notices.size(), 1u) << joined(imported.notices);
  EXPECT_NE(imported.notices[0].find("under-actuated: joint(s) 'j1' have no actuator"), std::string::npos)
      << imported.notices[0];
  // a passive joint is not an unbounded one
  EXPECT_TRUE(imported.actuation.unbounded_joints.empty() ||
              std::find(imported.actuation.unbounded_joints.begin(), imported.actuation.unbounded_joints.end(),
                        "j1") == imported.actuation.unbounded_joints.end());
  EXPECT_NE(imported.actuation.summary().find("under-actuated, 1 joint(s) without an actuator"), std::string::npos);
}

// direct torques drive the joints the model leaves without an actuator only on request;
// otherwise those joints stay passive
TEST_F(ImportTest, DirectTorquesOnAnUnderActuatedModelNeedTheConfirmation) {
  // an acrobot: the shoulder is passive
  const mj::ModelPtr m = mj::load_model(IDMPC_SOURCE_DIR "/tests/mujoco/fixtures/acrobot.xml");
  mj::ImportOptions options = direct_torques();
  const mj::ImportedModel passive = mj::import_model(m.get(), "acrobot.xml", options);
  EXPECT_TRUE(passive.actuation.direct);
  EXPECT_EQ(passive.actuation.passive_dofs, std::vector<int>{0});
  EXPECT_EQ(passive.model.unactuated_joints, std::vector<int>{0});
  EXPECT_EQ(passive.actuation.unbounded_joints, std::vector<std::string>{"elbow"});
  options.actuate_every_joint = true;
  const mj::ImportedModel imported = mj::import_model(m.get(), "acrobot.xml", options);
  EXPECT_TRUE(imported.actuation.direct);
  EXPECT_FALSE(imported.model.under_actuated());
  EXPECT_EQ(imported.actuation.unactuated_joints, std::vector<std::string>{"shoulder"});
  // the notice says so, and direct torques have no declared bound
  ASSERT_EQ(imported.notices.size(), 1u) << joined(imported.notices);
  EXPECT_NE(imported.notices[0].find("'shoulder'"), std::string::npos) << imported.notices[0];
  EXPECT_EQ(imported.actuation.unbounded_joints, (std::vector<std::string>{"shoulder", "elbow"}));
  // a fully actuated model needs no confirmation
  const mj::ModelPtr full = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor joint="j0"/><motor joint="j1"/><motor joint="j2"/>)"));
  EXPECT_NO_THROW(mj::import_model(full.get(), "full.xml", direct_torques()));
}

// servos are replaced by joint torques bounded by their force ranges; their control ranges are
// positions and velocities, no torques
TEST_F(ImportTest, ServosAreReplacedByJointTorquesLimitedByTheirForceRange) {
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor name="m0" joint="j0" gear="2" ctrllimited="true" ctrlrange="-1 1.5"/>
             <position name="servo1" joint="j1" kp="20" gear="-3" ctrllimited="true" ctrlrange="-0.1 0.1"
                       forcelimited="true" forcerange="-5 4"/>
             <velocity name="servo2" joint="j2" kv="3"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "servo.xml");
  const mj::Actuation& act = imported.actuation;
  EXPECT_TRUE(act.direct);
  EXPECT_EQ(act.replaced_servos, (std::vector<std::string>{"servo1", "servo2"}));
  const double inf = std::numeric_limits<double>::infinity();
  // motor: ctrl range × gain × gear; servo1: force range × gear (flipped); servo2: none
  EXPECT_EQ(act.torque_lower, (VecX<double>(3) << -2, -12, -inf).finished());
  EXPECT_EQ(act.torque_upper, (VecX<double>(3) << 3, 15, inf).finished());
  EXPECT_EQ(act.unbounded_joints, std::vector<std::string>{"j2"});
  ASSERT_EQ(imported.notices.size(), 1u) << joined(imported.notices);
  for (const std::string part : {"position and velocity servos 'servo1', 'servo2' replaced by joint torques",
                                 "forcerange × gear of 'servo1'", "'servo2' declare no forcerange"}) {
    EXPECT_NE(imported.notices[0].find(part), std::string::npos) << "lacks '" << part << "': " << imported.notices[0];
  }
  EXPECT_NE(act.summary().find("no torque limit declared for joint(s) 'j2'"), std::string::npos) << act.summary();
  // the joint's own torque range (actuatorfrcrange of a joint no actuator drives) bounds it too
  mj::ImportOptions options;
  options.joint_force_lower = {-inf, -inf, -7};
  options.joint_force_upper = {inf, inf, 6};
  const mj::ImportedModel ranged = mj::import_model(m.get(), "servo.xml", options);
  EXPECT_EQ(ranged.actuation.torque_lower[2], -7);
  EXPECT_EQ(ranged.actuation.torque_upper[2], 6);
  EXPECT_TRUE(ranged.actuation.unbounded_joints.empty());
  // torques applied directly on request: no replacement reported
  const mj::ImportedModel direct = mj::import_model(m.get(), "servo.xml", direct_torques());
  EXPECT_TRUE(direct.actuation.direct);
  EXPECT_TRUE(direct.actuation.replaced_servos.empty());
  EXPECT_EQ(direct.model.n, 3);
}

// unnamed servos are named "#id" in the notice, and their force ranges are found by that name
TEST_F(ImportTest, UnnamedServosAreReportedByTheirIndex) {
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor joint="j0" ctrllimited="true" ctrlrange="-1 1"/>
             <position joint="j1" kp="20" ctrllimited="true" ctrlrange="-1 1" forcelimited="true" forcerange="-5 4"/>
             <velocity joint="j2" kv="3" forcelimited="true" forcerange="-2 2"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "unnamed.xml");
  EXPECT_EQ(imported.actuation.replaced_servos, (std::vector<std::string>{"#1", "#2"}));
  ASSERT_EQ(imported.notices.size(), 1u) << joined(imported.notices);
  const std::string& notice = imported.notices[0];
  EXPECT_NE(notice.find("position and velocity servos '#1', '#2' replaced"), std::string::npos) << notice;
  EXPECT_NE(notice.find("limited by the forcerange × gear of '#1', '#2'"), std::string::npos) << notice;
  EXPECT_EQ(notice.find("declare no forcerange"), std::string::npos) << notice;
}

// joints without an actuator that an active joint equality ties to an actuated one (mimic
// joints, e.g. the second finger of a gripper): with servos they are driven by direct torques
// within their leader's range, said on one line grouped by the joint each follows; with motors
// the file is refused, naming them, with the option that drives them
std::string mimic_mjcf(const std::string& kind) {
  std::string bodies, equalities;
  for (int j = 0; j < 5; ++j) {
    bodies += "<body pos=\"0.2 0 0\"><joint name=\"j" + std::to_string(j) +
              "\" axis=\"0 1 0\" range=\"-1 1\"/><geom type=\"capsule\" fromto=\"0 0 0 0.2 0 0\" size=\"0.02\" mass=\"0.3\"/>";
  }
  for (int j = 0; j < 5; ++j) bodies += "</body>";
  for (const auto& [joint, leader] : {std::pair{"j1", "j0"}, {"j2", "j0"}, {"j4", "j3"}}) {
    equalities += std::string("<joint joint1=\"") + joint + "\" joint2=\"" + leader + "\" polycoef=\"0 1 0 0 0\"/>";
  }
  const std::string attributes = kind == "position" ? R"(kp="20" forcelimited="true" forcerange="-3 3")"
                                                    : R"(ctrllimited="true" ctrlrange="-3 3")";
  return "<mujoco><option timestep=\"0.001\"/><default><geom contype=\"0\" conaffinity=\"0\"/></default><worldbody>" +
         bodies + "</worldbody><equality>" + equalities + "</equality><actuator><" + kind + " joint=\"j0\" " +
         attributes + "/><" + kind + " joint=\"j3\" " + attributes + "/></actuator></mujoco>";
}

TEST_F(ImportTest, MimicJointsAreSaidOnceGroupedByTheJointTheyFollow) {
  const mj::ModelPtr servos = mj::load_model_from_string(mimic_mjcf("position"));
  const mj::ImportedModel imported = mj::import_model(servos.get(), "mimic.xml");
  using Pair = std::pair<std::string, std::string>;
  EXPECT_EQ(imported.actuation.coupled_joints, (std::vector<Pair>{{"j1", "j0"}, {"j2", "j0"}, {"j4", "j3"}}));
  const auto it = std::find_if(imported.notices.begin(), imported.notices.end(),
                               [](const std::string& n) { return n.find("equality") != std::string::npos; });
  ASSERT_NE(it, imported.notices.end()) << joined(imported.notices);
  EXPECT_EQ(it->rfind("joint(s) 'j1', 'j2' follow 'j0'; 'j4' follows 'j3': no actuator of their own", 0), 0u) << *it;
  EXPECT_EQ(std::count(it->begin(), it->end(), '('), std::count(it->begin(), it->end(), ')')) << *it;
  // driven within their leader's range
  EXPECT_EQ(imported.actuation.torque_upper[1], imported.actuation.torque_upper[0]);
  EXPECT_EQ(imported.actuation.torque_lower[4], imported.actuation.torque_lower[3]);

  const mj::ModelPtr motors = mj::load_model_from_string(mimic_mjcf("motor"));
  expect_throw_naming<std::invalid_argument>([&] { mj::import_model(motors.get(), "mimic.xml"); },
                                             {"mimic.xml", "'j1', 'j2' follow 'j0'; 'j4' follows 'j3'", "--direct-torque"});
}

// a servo without a forcerange but with a control range: the torque it gives at rest over its
// control range and its joint's range (the control range where the joint has none), times the
// gear; in MuJoCo the force is gain·ctrl + b0 + b1·q + b2·v (position: b1 = −kp; velocity: b2)
TEST_F(ImportTest, ServosWithoutAForceRangeAreLimitedByWhatTheyGiveAtRest) {
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<position name="p0" joint="j0" kp="20" gear="2" ctrllimited="true" ctrlrange="-0.5 1"/>
             <position name="p1" joint="j1" kp="50" ctrllimited="true" ctrlrange="-0.1 0.2"/>
             <velocity name="v2" joint="j2" kv="3" ctrllimited="true" ctrlrange="-2 1"/>)",
      R"(limited="false")"));
  // j0 given a range: the servo's force at rest over ctrl ∈ [-0.5, 1] and q ∈ [-0.3, 0.4]
  m->jnt_limited[0] = 1;
  m->jnt_range[0] = -0.3;
  m->jnt_range[1] = 0.4;
  const mj::ImportedModel imported = mj::import_model(m.get(), "servos.xml");
  const mj::Actuation& act = imported.actuation;
  EXPECT_EQ(act.derived_limits, (std::vector<std::string>{"p0", "p1", "v2"}));
  // p0: 20·(−0.5 − 0.4) = −18 … 20·(1 + 0.3) = 26, times gear 2
  EXPECT_DOUBLE_EQ(act.torque_lower[0], -36);
  EXPECT_DOUBLE_EQ(act.torque_upper[0], 52);
  // p1, no joint range: the control range as positions, 50·(−0.1 − 0.2) … 50·(0.2 + 0.1)
  EXPECT_DOUBLE_EQ(act.torque_lower[1], -15);
  EXPECT_DOUBLE_EQ(act.torque_upper[1], 15);
  // v2 at rest: 3·ctrl
  EXPECT_DOUBLE_EQ(act.torque_lower[2], -6);
  EXPECT_DOUBLE_EQ(act.torque_upper[2], 3);
  EXPECT_TRUE(act.unbounded_joints.empty());
  ASSERT_EQ(imported.notices.size(), 1u) << joined(imported.notices);
  EXPECT_NE(imported.notices[0].find("'p0', 'p1', 'v2' declare no forcerange: limited by the force they give at rest"),
            std::string::npos)
      << imported.notices[0];
}

TEST_F(ImportTest, MusclesAreRefusedAndServosOnAnUnderActuatedModelLeaveTheBareJointPassive) {
  const mj::ModelPtr muscle = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor name="m0" joint="j0"/><motor name="m1" joint="j1"/>
             <muscle name="biceps" joint="j2" lengthrange="0.1 1"/>)"));
  expect_throw_naming<std::invalid_argument>([&] { mj::import_model(muscle.get(), "muscle.xml"); },
                                             {"'biceps'", "neither a motor nor a servo", "--direct-torque"});
  const mj::ModelPtr servos = mj::load_model_from_string(
      chain_mjcf("", R"(<position name="s0" joint="j0" kp="10"/><position name="s2" joint="j2" kp="10"/>)"));
  EXPECT_EQ(mj::import_model(servos.get(), "servos.xml").model.unactuated_joints, std::vector<int>{1});
  mj::ImportOptions options;
  options.actuate_every_joint = true;
  const mj::ImportedModel imported = mj::import_model(servos.get(), "servos.xml", options);
  EXPECT_EQ(imported.actuation.replaced_servos, (std::vector<std::string>{"s0", "s2"}));
  EXPECT_EQ(imported.actuation.unactuated_joints, std::vector<std::string>{"j1"});
}

TEST_F(ImportTest, TendonActuatorIsRejected) {
  std::string xml = chain_mjcf("", R"(<motor name="m0" joint="j0"/><motor name="m1" joint="j1"/>
             <motor name="m2" joint="j2"/><motor name="pull" tendon="t"/>)");
  xml.insert(xml.find("<actuator>"), R"(<tendon><fixed name="t"><joint joint="j0" coef="1"/>
    <joint joint="j2" coef="-1"/></fixed></tendon>)");
  const mj::ModelPtr m = mj::load_model_from_string(xml);
  expect_throw_naming<std::invalid_argument>([&] { mj::import_model(m.get(), "tendon.xml"); },
                                             {"pull", "does not act on a joint", "tendon.xml"});
}

TEST_F(ImportTest, TwoMotorsOnOneJointAreRejected) {
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor name="m0" joint="j0"/><motor name="m0_again" joint="j0"/>
             <motor name="m1" joint="j1"/><motor name="m2" joint="j2"/>)"));
  expect_throw_naming<std::invalid_argument>([&] { mj::import_model(m.get(), "twice.xml"); },
                                             {"m0_again", "'j0'", "link0", "twice.xml"});
}

TEST_F(ImportTest, NoActuatorsMeansDirectTorques) {
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf("", ""));
  const mj::ImportedModel imported = mj::import_model(m.get(), "bare.xml");
  EXPECT_TRUE(imported.actuation.direct);
  EXPECT_EQ(imported.model.n, 3);
}

TEST_F(ImportTest, MotorsMapToTheirJointsWithGainTimesGear) {
  // listed out of dof order, with a general fixed-gain actuator among them
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor name="m2" joint="j2" gear="2.5"/><motor name="m0" joint="j0" gear="0.5"/>
             <general name="g1" joint="j1" gainprm="4" gear="2.5"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "motors.xml");
  ASSERT_FALSE(imported.actuation.direct);
  EXPECT_EQ(imported.actuation.actuator_of_dof, (std::vector<int>{1, 2, 0}));
  ASSERT_EQ(imported.actuation.ctrl_per_torque.size(), 3u);
  EXPECT_DOUBLE_EQ(imported.actuation.ctrl_per_torque[0], 1 / 0.5);
  EXPECT_DOUBLE_EQ(imported.actuation.ctrl_per_torque[1], 1 / (4 * 2.5));
  EXPECT_DOUBLE_EQ(imported.actuation.ctrl_per_torque[2], 1 / 2.5);
}

// ---------------------------------------------------------------------------------------------
// what the controller's model leaves out

TEST_F(ImportTest, UnmodeledReportListsLimitsContactsTendonsFrictionAndEqualities) {
  const mj::ModelPtr m = mj::load_model_from_string(R"(<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="arm" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" limited="true" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04" mass="1"/>
      <body name="hand" pos="0.4 0 0">
        <joint name="wrist" type="hinge" axis="0 1 0" frictionloss="0.1"/>
        <geom type="sphere" size="0.05" mass="0.3"/>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="coupling"><joint joint="shoulder" coef="1"/><joint joint="wrist" coef="1"/></fixed></tendon>
  <equality><joint joint1="shoulder" joint2="wrist"/></equality>
</mujoco>)");
  const mj::ImportedModel imported = mj::import_model(m.get(), "unmodeled.xml");
  const std::string report = joined(imported.unmodeled);
  EXPECT_NE(report.find("contacts"), std::string::npos) << report;
  EXPECT_NE(report.find("range limits on joint(s) 'shoulder'"), std::string::npos) << report;
  EXPECT_EQ(report.find("range limits on joint(s) 'shoulder', 'wrist'"), std::string::npos) << report;
  EXPECT_NE(report.find("friction loss on 1 joint(s) ('wrist') as a constraint with stiction"), std::string::npos)
      << report;
  EXPECT_NE(report.find("1 tendon"), std::string::npos) << report;
  EXPECT_NE(report.find("1 equality"), std::string::npos) << report;
  EXPECT_EQ(imported.unmodeled.size(), 5u) << report;
}

// actuator ranges are modelled: they become the torque limits the controller clamps to and
// are no longer reported as unmodeled
TEST_F(ImportTest, ActuatorRangesBecomeTorqueLimits) {
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor name="m0" joint="j0" gear="2" ctrllimited="true" ctrlrange="-1 1.5"/>
             <motor name="m1" joint="j1" gear="-3" forcelimited="true" forcerange="-5 4"/>
             <motor name="m2" joint="j2"/>)"));
  const mj::ImportedModel motors = mj::import_model(m.get(), "ranges.xml");
  EXPECT_TRUE(motors.unmodeled.empty()) << joined(motors.unmodeled);
  const double inf = std::numeric_limits<double>::infinity();
  // ctrl range × gain × gear; force range × gear (a negative gear flips the interval)
  EXPECT_EQ(motors.actuation.torque_lower, (VecX<double>(3) << -2, -12, -inf).finished());
  EXPECT_EQ(motors.actuation.torque_upper, (VecX<double>(3) << 3, 15, inf).finished());
  // torques applied directly bypass the actuators and their ranges
  const mj::ImportedModel direct = mj::import_model(m.get(), "ranges.xml", direct_torques());
  EXPECT_TRUE(direct.unmodeled.empty());
  EXPECT_EQ(direct.actuation.torque_upper, VecX<double>::Constant(3, inf));
}

TEST_F(ImportTest, ShippedAndRandomModelsHaveNothingUnmodeled) {
  // the paper's models are written for the controller: no contacts, tendons, friction loss...
  // The real arms (mjcf/panda.xml, ...) keep their joint ranges, and those published for MuJoCo 3
  // (mjcf/fr3.xml, ...) their collision geoms and joint friction: plant features the controller
  // does not model (their torque limits, from the actuators, it models)
  const auto allowed = [](const std::string& item) {
    return item.rfind("range limits on ", 0) == 0 || item.rfind("contacts (", 0) == 0 ||
           item.rfind("friction loss on ", 0) == 0;
  };
  for (const std::string& path : test::shipped_model_paths()) {
    const mj::ModelPtr m = test::load_problem(path).m;  // a gripper's held joints welded
    const mj::ImportedModel imported = mj::import_model(m.get(), path);
    bool ranged = false;
    for (int u = 0; u < m->nu; ++u) ranged = ranged || m->actuator_ctrllimited[u];
    if (!ranged) {
      EXPECT_TRUE(imported.unmodeled.empty()) << path << ":" << joined(imported.unmodeled);
      continue;
    }
    for (const std::string& item : imported.unmodeled) {
      EXPECT_TRUE(allowed(item)) << path << ": " << item;
    }
  }
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const mj::ModelPtr m = mj::load_model_from_string(test::random_tree_mjcf(seed));
    const mj::ImportedModel imported = mj::import_model(m.get(), "random tree");
    EXPECT_TRUE(imported.unmodeled.empty()) << "seed " << seed << ":" << joined(imported.unmodeled);
  }
}

// ---------------------------------------------------------------------------------------------
// option flags

TEST_F(ImportTest, DisabledGravityGivesZeroGravityAndMatchesMujoco) {
  const mj::ModelPtr m = mj::load_model_from_string(
      chain_mjcf(R"(<flag gravity="disable"/>)", "", R"(damping="0.2" armature="0.05")"));
  const Model model = mj::import_model(m.get(), "no_gravity.xml").model;
  EXPECT_EQ(model.gravity, Vec3<double>::Zero());
  Data data(model);
  mj::Reference ref(m.get());
  std::mt19937 rng(7);
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const VecX<double> q = model.q_ref + random_vector(rng, 3, 3.0),
                       v = random_vector(rng, 3, 2.0), a = random_vector(rng, 3, 5.0);
    EXPECT_LE(rel(rnea(model, data, q, v, a), ref.inverse(q, v, a)), kMujoco);
    // at rest with no acceleration nothing needs holding
    const VecX<double> zero = VecX<double>::Zero(3);
    EXPECT_LE(rnea(model, data, q, zero, zero).cwiseAbs().maxCoeff(), kMujoco);
  }
  expect_check_model_ok(m.get(), model, "no_gravity");
}

TEST_F(ImportTest, TiltedGravityMatchesMujoco) {
  const mj::ModelPtr m = mj::load_model_from_string(R"(<mujoco>
  <option gravity="1.5 -2 -7"/>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="link0" pos="0 0 1" euler="0.3 0.2 0.1">
      <joint name="j0" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04" mass="1"/>
      <body name="link1" pos="0.4 0 0">
        <joint name="j1" type="slide" axis="1 0 0.5"/>
        <geom type="sphere" pos="0.1 0 0" size="0.05" mass="0.6"/>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  const Model model = mj::import_model(m.get(), "tilted.xml").model;
  EXPECT_EQ(model.gravity, Vec3<double>(1.5, -2, -7));
  expect_check_model_ok(m.get(), model, "tilted");
}

TEST_F(ImportTest, DisabledPassiveForcesZeroDampingAndStiffness) {
  const std::string joints = R"(damping="0.7" stiffness="3" springref="0.2" armature="0.05")";
  const mj::ModelPtr with = mj::load_model_from_string(chain_mjcf("", "", joints));
  const Model model_with = mj::import_model(with.get(), "passive.xml").model;
  // the flag is what zeroes them
  EXPECT_GT(model_with.damping.minCoeff(), 0.0);
  EXPECT_GT(model_with.stiffness.minCoeff(), 0.0);

  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(R"(<flag passive="disable"/>)", "", joints));
  const Model model = mj::import_model(m.get(), "no_passive.xml").model;
  EXPECT_EQ(model.damping, VecX<double>::Zero(3));
  EXPECT_EQ(model.stiffness, VecX<double>::Zero(3));
  EXPECT_EQ(model.armature, model_with.armature);  // armature is inertia, not a passive force
  Data data(model);
  mj::Reference ref(m.get());
  std::mt19937 rng(8);
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const VecX<double> q = model.q_ref + random_vector(rng, 3, 3.0),
                       v = random_vector(rng, 3, 2.0), a = random_vector(rng, 3, 5.0),
                       tau = random_vector(rng, 3, 5.0);
    EXPECT_LE(rel(rnea(model, data, q, v, a), ref.inverse(q, v, a)), kMujoco);
    EXPECT_LE(rel(aba(model, data, q, v, tau), ref.forward(q, v, tau)), kMujoco);
  }
  expect_check_model_ok(m.get(), model, "no_passive");
}

// ---------------------------------------------------------------------------------------------
// the tree

/// the masses each link must carry: every body welded to a jointed body, summed, on the last
/// link of that body's joints; bodies welded to the world carry nothing
void expect_welded_masses_merged(const mjModel* m, const Model& model, const std::string& label) {
  SCOPED_TRACE(label);
  VecX<double> expected = VecX<double>::Zero(model.n);
  double total = 0;
  for (int b = 1; b < m->nbody; ++b) {
    const int weld = m->body_weldid[b];
    if (weld == 0) continue;
    ASSERT_GT(m->body_jntnum[weld], 0);
    const int last_dof = m->jnt_dofadr[m->body_jntadr[weld] + m->body_jntnum[weld] - 1];
    expected[last_dof] += m->body_mass[b];
    total += m->body_mass[b];
  }
  double links = 0;
  for (int i = 0; i < model.n; ++i) {
    EXPECT_NEAR(model.I[i].m, expected[i], kMassSum) << "link " << i << " ('"
                                                       << model.joint_names[i] << "')";
    links += model.I[i].m;
  }
  EXPECT_NEAR(links, total, kMassSum * m->nbody);
}

TEST_F(ImportTest, WeldedBodyMassesMergeIntoTheirLinks) {
  for (const std::string& path : test::shipped_model_paths()) {
    const mj::ModelPtr m = test::load_problem(path).m;  // a gripper's held joints welded
    expect_welded_masses_merged(m.get(), mj::import_model(m.get(), path).model, path);
  }
  for (unsigned seed = 1; seed <= 50; ++seed) {
    const mj::ModelPtr m = mj::load_model_from_string(test::random_tree_mjcf(seed));
    expect_welded_masses_merged(m.get(), mj::import_model(m.get(), "random tree").model,
                                "random tree seed " + std::to_string(seed));
  }
}

TEST_F(ImportTest, WeldedBodiesOnTheWorldCarryNothing) {
  // a heavy jointless body on the world, and one between the world and a jointed body
  const mj::ModelPtr m = mj::load_model_from_string(R"(<mujoco>
  <worldbody>
    <body name="stand" pos="0 0 0.5"><geom type="box" size="0.1 0.1 0.5" mass="50"/></body>
    <body name="mount" pos="0 0 1" euler="0.3 0 0">
      <geom type="box" size="0.05 0.05 0.05" mass="5"/>
      <body name="arm" pos="0 0.1 0">
        <joint name="shoulder" type="hinge" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0 0.4 0" size="0.03" mass="1.25"/>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  const Model model = mj::import_model(m.get(), "stand.xml").model;
  ASSERT_EQ(model.n, 1);
  EXPECT_NEAR(model.I[0].m, 1.25, kMassSum);
  expect_check_model_ok(m.get(), model, "stand");
}

constexpr const char* kMultiJointBody = R"(<mujoco model="multi_joint">
  <option timestep="0.001"><flag contact="disable"/></option>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="base" pos="0.1 0.2 1" quat="0.9 0.1 0.3 -0.2">
      <joint name="a" type="hinge" pos="0.05 0 0.02" axis="1 0.2 0.1" damping="0.1"/>
      <joint name="b" type="slide" pos="-0.03 0.04 0" axis="0.1 1 0.3" stiffness="2"
             springref="0.1"/>
      <joint name="c" type="hinge" pos="0 -0.05 0.1" axis="0.3 -0.2 1" armature="0.02"
             ref="0.3"/>
      <inertial pos="0.1 0.02 -0.03" quat="0.8 0.2 0.1 0.3" mass="1.5"
                diaginertia="0.03 0.02 0.015"/>
      <body name="tip" pos="0.3 0 0" euler="0.2 0.1 0">
        <joint name="d" type="hinge" pos="0.02 0.01 0" axis="0 1 0.2"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.03" mass="0.5"/>
      </body>
    </body>
  </worldbody>
</mujoco>)";

TEST_F(ImportTest, SeveralJointsInOneBodyMatchMujoco) {
  const mj::ModelPtr m = mj::load_model_from_string(kMultiJointBody);
  const Model model = mj::import_model(m.get(), "multi_joint.xml").model;
  ASSERT_EQ(model.n, 4);
  EXPECT_EQ(model.parent, (std::vector<int>{-1, 0, 1, 2}));
  EXPECT_EQ(model.joint_type[1], JointType::kPrismatic);
  // the body's inertia sits on its last joint's link
  EXPECT_EQ(model.I[0].m, 0.0);
  EXPECT_EQ(model.I[1].m, 0.0);
  EXPECT_NEAR(model.I[2].m, 1.5, kMassSum);
  expect_check_model_ok(m.get(), model, "multi_joint");
}

// ---------------------------------------------------------------------------------------------
// the plant: a torque τ reaches MuJoCo as exactly τ

constexpr const char* kPlantJoints = R"(
      <joint name="j0" type="hinge" axis="0 1 0.2" stiffness="1" springref="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 -0.1" size="0.04" mass="1"/>
      <body name="l1" pos="0.4 0 -0.1" euler="0.2 0 0.1">
        <joint name="j1" type="slide" axis="1 0.3 0.1" armature="0.1"/>
        <geom type="box" pos="0.1 0 0" size="0.1 0.05 0.05" mass="0.7"/>
        <body name="l2" pos="0.2 0 0">
          <joint name="j2" type="hinge" pos="0.01 0 0" axis="0.3 0.2 1"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.03" mass="0.5"/>
        </body>
      </body>)";

// no damping: MuJoCo's Euler integrator would treat it implicitly, and v₁ − v₀ ≠ Δt·qacc
std::string plant_mjcf(const std::string& actuators) {
  return std::string(R"(<mujoco model="plant">
  <option timestep="0.002" integrator="Euler"><flag contact="disable"/></option>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="l0" pos="0 0 1">)") + kPlantJoints + R"(
    </body>
  </worldbody>
  <actuator>)" + actuators + R"(</actuator>
</mujoco>)";
}

/// one plant step from random states: (v₁ − v₀)/Δt equals MuJoCo's qacc under qfrc_applied = τ
void expect_plant_applies_torques(const mjModel* m, const mj::Actuation& actuation,
                                  const std::string& label) {
  SCOPED_TRACE(label);
  mj::Plant plant(m, actuation);
  mj::Reference ref(m);
  const int n = m->nv;
  const Eigen::Map<const VecX<double>> qpos0(m->qpos0, m->nq);
  std::mt19937 rng(11);
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const VecX<double> q = qpos0 + random_vector(rng, n, 1.0), v = random_vector(rng, n, 1.0),
                       tau = random_vector(rng, n, 5.0);
    plant.reset(q, v);
    std::string reason;
    ASSERT_TRUE(plant.step(tau, &reason)) << reason;
    const VecX<double> qacc = (plant.v() - v) / plant.timestep();
    EXPECT_LE(rel(qacc, ref.forward(q, v, tau)), kPlantAcceleration)
        << "plant " << qacc.transpose() << "\nreference " << ref.forward(q, v, tau).transpose();
  }
}

TEST_F(ImportTest, PlantWithDirectTorquesAppliesTau) {
  const mj::ModelPtr m = mj::load_model_from_string(plant_mjcf(""));
  const mj::ImportedModel imported = mj::import_model(m.get(), "plant.xml");
  ASSERT_TRUE(imported.actuation.direct);
  expect_plant_applies_torques(m.get(), imported.actuation, "no actuators");
}

TEST_F(ImportTest, PlantWithDirectTorquesIgnoresTheModelsServos) {
  const mj::ModelPtr m = mj::load_model_from_string(plant_mjcf(
      R"(<position joint="j0" kp="50"/><position joint="j1" kp="50"/><velocity joint="j2" kv="3"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "plant.xml", direct_torques());
  ASSERT_TRUE(imported.actuation.direct);
  expect_plant_applies_torques(m.get(), imported.actuation, "servos, direct torques");
}

TEST_F(ImportTest, PlantWithGearedMotorsScalesCtrl) {
  const mj::ModelPtr m = mj::load_model_from_string(plant_mjcf(
      R"(<motor joint="j2" gear="2.5"/><motor joint="j0" gear="2.5"/><motor joint="j1" gear="2.5"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "plant.xml");
  ASSERT_FALSE(imported.actuation.direct);
  expect_plant_applies_torques(m.get(), imported.actuation, "motors with gear 2.5");
}

TEST_F(ImportTest, PlantWithMixedGainsAndGearsScalesCtrl) {
  const mj::ModelPtr m = mj::load_model_from_string(plant_mjcf(
      R"(<motor joint="j1" gear="0.4"/><general joint="j2" gainprm="3" gear="2.5"/>
         <motor joint="j0" gear="-1.5"/>)"));
  const mj::ImportedModel imported = mj::import_model(m.get(), "plant.xml");
  ASSERT_FALSE(imported.actuation.direct);
  expect_plant_applies_torques(m.get(), imported.actuation, "mixed gains and gears");
}

// ---------------------------------------------------------------------------------------------
// hostile models: non-finite numbers, degenerate gears, newer MuJoCo, missing and huge assets

TEST_F(ImportTest, NonFiniteAxisIsRejectedNamingTheJoint) {
  std::string xml = chain_mjcf("", "");
  xml.replace(xml.find(R"(axis="1 0.3 0.1")"), 16, R"(axis="nan 1 0")");
  // the loader refuses the file (MuJoCo itself only warns) ...
  expect_throw_naming<std::runtime_error>([&] { mj::load_model_from_string(xml); },
                                          {"<joint> 'j1'", "line 9", "axis=\"nan 1 0\""});
  // ... and the importer a compiled model with such a value
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf("", ""));
  m->jnt_axis[3] = std::numeric_limits<double>::quiet_NaN();
  expect_throw_naming<std::invalid_argument>([&] { mj::import_model(m.get(), "nan.xml"); },
                                             {"'j1'", "link1", "axis", "nan", "nan.xml"});
}

TEST_F(ImportTest, DenormalZeroAndNonFiniteGearsAreRejectedNamingTheActuator) {
  for (const std::string gear : {"1e-320", "1e-13", "0", "-1e-300"}) {
    SCOPED_TRACE("gear " + gear);
    const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
        "", R"(<motor name="m0" joint="j0"/><motor name="tiny" joint="j1" gear=")" + gear +
                R"("/><motor name="m2" joint="j2"/>)"));
    expect_throw_naming<std::invalid_argument>([&] { mj::import_model(m.get(), "gear.xml"); },
                                               {"'tiny'", "gear", "1e-12", "gear.xml"});
  }
  // a small but sane gear is fine, and so are torques applied directly
  const mj::ModelPtr m = mj::load_model_from_string(chain_mjcf(
      "", R"(<motor joint="j0" gear="1e-3"/><motor joint="j1" gear="-2e-6"/><motor joint="j2"/>)"));
  EXPECT_NO_THROW(mj::import_model(m.get(), "small_gear.xml"));
}

TEST_F(ImportTest, RelativeErrorOfNonFiniteValuesIsNan) {
  VecX<double> x = VecX<double>::Ones(3), y = VecX<double>::Ones(3);
  EXPECT_EQ(mj::relative_error(x, y), 0.0);
  for (const double bad : {NAN, INFINITY}) {
    x[1] = bad;
    EXPECT_TRUE(std::isnan(mj::relative_error(x, y))) << bad;
    EXPECT_TRUE(std::isnan(mj::relative_error(y, x))) << bad;
  }
}

TEST_F(ImportTest, ACheckEntryKeepsANanErrorAndFails) {
  mj::CheckEntry e{"quantity", 0, 1e-10};
  e.record(1e-12);
  EXPECT_TRUE(e.ok());
  e.record(NAN);  // std::max(worst, NaN) would keep 1e-12
  e.record(1e-13);
  EXPECT_TRUE(std::isnan(e.worst));
  EXPECT_FALSE(e.ok());
}

// fluid forces and tendon springs are listed as unmodeled; check_model compares against a MuJoCo
// without them
TEST_F(ImportTest, CheckModelComparesWithoutFluidForcesAndTendonSprings) {
  std::string fluid = chain_mjcf("", "");
  fluid.replace(fluid.find(R"(<option timestep="0.001">)"), 25,
                R"(<option timestep="0.001" density="1000" viscosity="0.5" wind="0.5 0 0">)");
  std::string tendon = chain_mjcf("", "");
  tendon.insert(tendon.find("<actuator>"), R"(<tendon><fixed name="spring" stiffness="40" damping="2">
    <joint joint="j0" coef="1"/><joint joint="j2" coef="-0.5"/></fixed></tendon>)");
  for (const auto& [xml, feature] : {std::make_pair(fluid, std::string("fluid forces (density/viscosity)")),
                                     std::make_pair(tendon, std::string("tendon springs and dampers"))}) {
    SCOPED_TRACE(feature);
    const mj::ModelPtr m = mj::load_model_from_string(xml);
    const mj::ImportedModel imported = mj::import_model(m.get(), "unmodeled.xml");
    EXPECT_EQ(mj::reference_simplifications(m.get()), std::vector<std::string>{feature});
    expect_check_model_ok(m.get(), imported.model, feature);
  }
  // the shipped models need no simplification
  for (const std::string& path : test::shipped_model_paths()) {
    const mj::ModelPtr m = mj::load_model(path);
    EXPECT_TRUE(mj::reference_simplifications(m.get()).empty()) << path;
  }
}

/// a model file in a fresh directory, removed with it
class LoaderTest : public ImportTest {
 protected:
  void SetUp() override {
    ImportTest::SetUp();
    dir_ = ::testing::TempDir() + "idmpc_loader_test_" + std::to_string(::getpid()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "/";
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::filesystem::remove_all(dir_);
    ImportTest::TearDown();
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ + name, std::ios::binary) << text;
    return dir_ + name;
  }
  // chain_mjcf with `assets` (compiler, asset, include elements) inside <mujoco>
  std::string model_with(const std::string& assets) const {
    std::string xml = chain_mjcf("", "");
    xml.insert(xml.find("<default>"), assets + "\n  ");
    return write("model.xml", xml);
  }
  // the message of load_model's exception; "" if it loaded
  static std::string load_error(const std::string& path) {
    try {
      mj::load_model(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  std::string dir_;
};

TEST_F(LoaderTest, NewerMujocoAttributesValuesAndElementsAreNamed) {
  const std::string version = mj_versionString();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(<compiler maxhullvert="8"/>)", "attribute 'maxhullvert' (<compiler>, line 3)"},
      {R"(<option><flag eulerdamp="disable"/></option>)", "attribute 'eulerdamp' (<flag>, line 3)"},
      {R"(<replicate count="2"/>)", "element <replicate>, line 3"}};
  for (const auto& [assets, needle] : cases) {
    SCOPED_TRACE(assets);
    const std::string message = load_error(model_with(assets));
    for (const std::string& part : {needle, std::string("needs a newer MuJoCo"), "this build uses MuJoCo " + version}) {
      EXPECT_NE(message.find(part), std::string::npos) << "lacks '" << part << "': " << message;
    }
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  // a name MuJoCo never had: misspelled or newer
  std::string xml = chain_mjcf("", R"(<motor joint="j0" gaer="2"/>)");
  const std::string message = load_error(write("typo.xml", xml));
  EXPECT_NE(message.find("attribute 'gaer'"), std::string::npos) << message;
  EXPECT_NE(message.find("misspelled"), std::string::npos) << message;
}

TEST_F(LoaderTest, MissingMeshAndTextureFilesAreNamed) {
  std::string message = load_error(model_with(
      R"(<compiler meshdir="meshes"/><asset><mesh name="hand" file="hand.stl"/></asset>)"));
  EXPECT_NE(message.find("mesh file '" + dir_ + "meshes/hand.stl' does not exist"), std::string::npos) << message;
  EXPECT_NE(message.find("'hand'"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  message = load_error(model_with(R"(<asset><texture name="wood" type="2d" file="textures/wood.png"/></asset>)"));
  EXPECT_NE(message.find("texture file '" + dir_ + "textures/wood.png' does not exist"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST_F(LoaderTest, HugeTexturesAndHeightFieldsAreRefusedBeforeLoading) {
  // 9000² pixels: above the bound, still small enough for MuJoCo to load without it
  std::string message = load_error(
      model_with(R"(<asset><texture name="sky" type="skybox" builtin="gradient" width="9000" height="9000"/></asset>)"));
  for (const std::string part : {"'sky'", "9000x9000", "8192x8192", "line 3"}) {
    EXPECT_NE(message.find(part), std::string::npos) << "lacks '" << part << "': " << message;
  }
  // in an included file
  write("big_asset.xml", R"(<mujoco><asset>
  <texture name="floor" type="2d" builtin="checker" width="100000" height="100000"/>
</asset></mujoco>)");
  message = load_error(model_with(R"(<include file="big_asset.xml"/>)"));
  EXPECT_NE(message.find("'floor'"), std::string::npos) << message;
  EXPECT_NE(message.find("big_asset.xml line 2"), std::string::npos) << message;
  // a PNG whose header claims 40000 x 40000 pixels
  std::string png("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x9c\x40\0\0\x9c\x40\x08\x02\0\0\0", 29);
  write("huge.png", png);
  message = load_error(model_with(R"(<asset><texture name="photo" type="2d" file="huge.png"/></asset>)"));
  EXPECT_NE(message.find("'photo'"), std::string::npos) << message;
  EXPECT_NE(message.find("40000x40000"), std::string::npos) << message;
  // a height field
  message = load_error(model_with(R"(<asset><hfield name="terrain" nrow="20000" ncol="20000" size="1 1 1 1"/></asset>)"));
  EXPECT_NE(message.find("'terrain'"), std::string::npos) << message;
  // textures within the bound load
  EXPECT_EQ(load_error(model_with(
                R"(<asset><texture name="sky" type="skybox" builtin="gradient" width="512" height="3072"/></asset>)")),
            "");
}

TEST_F(LoaderTest, ScannerSkipsCommentsAndCountsLines) {
  const std::vector<mj::MjcfElement> elements = mj::scan_elements(
      "<mujoco>\n<!-- <texture width=\"99999\"/> -->\n<asset a = 'x>y' b=\"2\">\n</asset></mujoco>", "f.xml");
  ASSERT_EQ(elements.size(), 2u);
  EXPECT_EQ(elements[1].name, "asset");
  EXPECT_EQ(elements[1].line, 3);
  EXPECT_EQ(elements[1].get("a"), "x>y");
  EXPECT_EQ(elements[1].get("b"), "2");
  EXPECT_EQ(elements[1].get("c", "none"), "none");
}

}  // namespace
}  // namespace idmpc
