// Joints the controller holds (a gripper's fingers driven through a tendon actuator): which
// joints the rule picks, the welded controller's model against MuJoCo's rows of the whole model
// (hinge and slide joints held away from their reference), and the closed loop on the Menagerie
// Panda with its hand, whose fingers the plant's own tendon servo holds.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/hold.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/task_run.hpp"
#include "support/errors.hpp"

namespace idmpc {
namespace {

const std::string kPandaHand = IDMPC_SOURCE_DIR "/mjcf/panda_hand.xml";
const std::string kPandaHandReach = IDMPC_SOURCE_DIR "/mjcf/panda_hand_reach.json";
const std::string kPandaHandCircle = IDMPC_SOURCE_DIR "/mjcf/panda_hand_circle.json";

std::vector<std::string> names(const mj::HeldJoints& h) { return h.names; }

// a two-joint arm with a gripper: a hinge finger whose anchor is off the body origin, with a
// tilted axis and a reference angle, and a slide finger; a fixed tendon sums the hinge finger
// alone, a joint equality ties the slide finger to it, a servo drives the tendon. `carried`
// goes into the hinge finger's body (a body with a joint `wrist` and a motor of its own)
std::string gripper_arm(bool carried = false) {
  const std::string wrist = carried ? R"(<body name="tip" pos="0 0 0.05"><joint name="wrist" axis="1 0 0"/>
              <geom type="sphere" size="0.01" mass="0.01"/></body>)"
                                    : "";
  return R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="l1" pos="0 0 0.1">
      <joint name="j1" axis="0 0 1" damping="0.5" armature="0.02"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04" mass="2"/>
      <body name="l2" pos="0.3 0 0" euler="0.3 0 0">
        <joint name="j2" axis="0 1 0" damping="0.5"/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.035" mass="1.2"/>
        <body name="hand" pos="0.25 0 0">
          <geom type="box" size="0.03 0.05 0.02" mass="0.4"/>
          <body name="finger_a" pos="0.02 0.03 0" euler="0 0.2 0.4">
            <joint name="fa" type="hinge" axis="0.3 1 0.2" pos="0.01 -0.02 0.005" ref="0.3" range="-1 1" damping="0.1"/>
            <geom type="box" size="0.01 0.005 0.03" pos="0.02 0 0.03" mass="0.05"/>)" +
         wrist + R"(
          </body>
          <body name="finger_b" pos="0.02 -0.03 0" quat="0 0 0 1">
            <joint name="fb" type="slide" axis="0.2 1 0.1" range="0 0.04" ref="0.01"/>
            <geom type="box" size="0.01 0.005 0.03" pos="0.01 0.01 0.03" mass="0.07"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="grip"><joint joint="fa" coef="1"/></fixed></tendon>
  <equality><joint joint1="fb" joint2="fa" polycoef="0.02 0.01 0 0 0"/></equality>
  <actuator>
    <motor name="m1" joint="j1" ctrlrange="-20 20"/>
    <motor name="m2" joint="j2" ctrlrange="-20 20"/>
    <general name="grip" tendon="grip" ctrlrange="-1 1" gainprm="10" biastype="affine" biasprm="0 -10 -1"/>)" +
         std::string(carried ? R"(<motor name="mw" joint="wrist"/>)" : "") + R"(
  </actuator>
  <keyframe><key name="home" qpos=")" +
         (carried ? "0.2 -0.4 0.7 0 0.03" : "0.2 -0.4 0.7 0.03") + R"("/></keyframe>
</mujoco>)";
}

std::string write_model(const std::string& name, const std::string& xml) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << xml;
  return path;
}

TEST(HeldJoints, TheRulePicksTheFingersATendonActuatorMovesAndTheirEqualities) {
  const mj::ModelPtr panda = mj::load_model(kPandaHand);
  const std::vector<int> fingers = mj::joints_to_hold(panda.get(), kPandaHand);
  const mj::HeldJoints held = mj::hold_joints(panda.get(), fingers, mj::keyframe_qpos(panda.get(), "home", kPandaHand));
  EXPECT_EQ(names(held), (std::vector<std::string>{"finger_joint1", "finger_joint2"}));
  EXPECT_DOUBLE_EQ(held.q[0], 0.04);
  EXPECT_DOUBLE_EQ(held.q[1], 0.04);
  // the servo's rest at the tendon length 0.04: 100·0.04/0.01568627451 = 255, its keyframe's ctrl
  ASSERT_EQ(held.actuators, std::vector<int>{7});
  EXPECT_NEAR(held.ctrl[0], 255.0, 1e-6);
  EXPECT_EQ(held.dof_of, (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(held.actuator_of, (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));

  // the slide finger is not on the tendon: the equality ties it to the hinge finger
  const std::string path = write_model("gripper_arm.xml", gripper_arm());
  const mj::ModelPtr arm = mj::load_model(path);
  const mj::HeldJoints h = mj::hold_joints(arm.get(), mj::joints_to_hold(arm.get(), path), mj::keyframe_qpos(arm.get(), "home", path));
  EXPECT_EQ(names(h), (std::vector<std::string>{"fa", "fb"}));
  // rest of the servo at the tendon length 0.7: ctrl = 10·0.7/10
  EXPECT_NEAR(h.ctrl[0], 0.7, 1e-12);
}

// the welded model's inverse dynamics and mass matrix are the rows of the whole model with the
// fingers where held and at rest: the welds of a hinge (anchor off the body origin, tilted axis,
// reference angle) and of a slide are MuJoCo's own kinematics. MuJoCo compiles the welded text,
// so check_model compares it with itself as for any model, and check_held with the whole model
TEST(HeldJoints, TheWeldedModelIsTheWholeModelWithTheFingersHeld) {
  const std::string path = write_model("gripper_arm.xml", gripper_arm());
  for (const std::string& file : {path, kPandaHand}) {
    const mj::LoadedModel full = mj::load_model_translated(file);
    const mjModel* m = full.model.get();
    const mj::HeldJoints held = mj::hold_joints(m, mj::joints_to_hold(m, file), mj::keyframe_qpos(m, "home", file));
    const mj::LoadedModel welded = mj::load_held_model(file, m, held);
    EXPECT_EQ(welded.model->nv, m->nv - 2) << file;
    EXPECT_EQ(welded.model->neq, 0) << file << ": the joint equality goes with its joints";
    EXPECT_EQ(welded.model->ntendon, 0) << file;
    const mj::ImportedModel imported = mj::import_model(welded.model.get(), file);
    for (const auto& e : mj::check_held(m, held, imported.model, 10, 3)) {
      EXPECT_TRUE(e.ok()) << file << ": " << e.quantity << " " << e.worst;
    }
    for (const auto& e : mj::check_model(welded.model.get(), imported.model, 5, 3)) {
      EXPECT_TRUE(e.ok()) << file << ": " << e.quantity << " " << e.worst;
    }
  }
}

// a Robotiq 2F-85 on a UR5e (tests/mujoco/fixtures/ur5e_2f85.xml): the tendon moves the two
// drivers; their joint equality, and the connect equalities that close each four-bar linkage,
// bring in the couplers, spring links and followers: all eight joints held. The welded model is
// the whole one's rows, and its connect equalities, now within one rigid body, are not reported as
// unmodeled
TEST(HeldJoints, AClosedLinkageGripperIsHeldWhole) {
  const std::string file = IDMPC_SOURCE_DIR "/tests/mujoco/fixtures/ur5e_2f85.xml";
  const mj::ControllerModel models = mj::load_controller_model(file, "home");
  const std::vector<std::string> expected = {"right_driver_joint", "right_coupler_joint", "right_spring_link_joint",
                                             "right_follower_joint", "left_driver_joint", "left_coupler_joint",
                                             "left_spring_link_joint", "left_follower_joint"};
  EXPECT_EQ(models.held.names, expected);
  ASSERT_EQ(models.model()->nv, 6);
  const mj::ImportedModel imported = mj::import_model(models.model(), file);
  for (const auto& e : mj::check_held(models.full.model.get(), models.held, imported.model, 10, 5)) {
    EXPECT_TRUE(e.ok()) << e.quantity << " " << e.worst;
  }
  for (const std::string& item : imported.unmodeled) {
    EXPECT_EQ(item.find("equality"), std::string::npos) << item;
  }
}

// a held joint may carry held joints only, and a body's joints are held all or none
TEST(HeldJoints, AHeldJointCarryingADrivenJointIsRefusedNamingBoth) {
  const std::string path = write_model("gripper_carrying.xml", gripper_arm(true));
  const mj::ModelPtr m = mj::load_model(path);
  const std::string msg = test::error_of([&] { mj::joints_to_hold(m.get(), path); });
  EXPECT_NE(msg.find("'fa'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'wrist'"), std::string::npos) << msg;
}

// the Panda with its hand as published: the controller's model has the arm's 7 joints, the
// plant all 9, the fingers held open by their own servo while the arm reaches
TEST(HeldJoints, ThePandaReachesWithItsFingersHeldByTheirServo) {
  Task task = load_task(kPandaHandReach);
  task.duration = 3.0;
  mj::TaskRun run(task);
  EXPECT_EQ(run.n(), 7);
  EXPECT_EQ(run.plant_model()->nv, 9);
  EXPECT_EQ(run.mj_model()->nv, 7);
  EXPECT_EQ(run.plant().nv(), 7);
  const mj::RunResult r = run.run();
  ASSERT_FALSE(r.diverged) << r.divergence_reason;
  const auto q = run.plant().full_q();
  EXPECT_NEAR(q[7], 0.04, 1e-3) << "finger held open";
  EXPECT_NEAR(q[8], 0.04, 1e-3) << "finger held open";
  EXPECT_LT((run.plant().q() - run.settings().q_ref).cwiseAbs().maxCoeff(), 5e-3) << "the arm reaches its target";
  const RunSummary s = run.summary(r);
  EXPECT_EQ(s.held_joints, (std::vector<std::string>{"finger_joint1", "finger_joint2"}));
  EXPECT_EQ(s.held_q, (std::vector<double>{0.04, 0.04}));
  // the log's joints by name and kind, and the solver, in the summary's JSON
  const nlohmann::json j = to_json(s);
  EXPECT_EQ(j.at("solver"), "riccati") << "the default solver on a fully actuated arm";
  EXPECT_EQ(j.at("joint_names").size(), 7u);
  EXPECT_EQ(j.at("joint_names")[0], "joint1");
  EXPECT_EQ(j.at("joint_types"), nlohmann::json(std::vector<std::string>(7, "hinge")));
  EXPECT_EQ(summary_from_json(j, "test").held_joints, s.held_joints);
  bool said = false;
  for (const auto& n : run.notices()) said = said || n.find("'finger_joint1' at 0.04") != std::string::npos;
  EXPECT_TRUE(said) << "a notice names the held joints";
}

// the shipped circle task of the Panda with its hand, as given (model, start, frame, circle;
// everything else the defaults), under FD and ID: the hand within 5 mm RMS, every torque the
// plant received within its actuator's range, the fingers still held open (acceptance tier)
TEST(HeldJoints, ThePandaHandTracksItsCircleUnderFdAndId) {
  for (const char* formulation : {"fd", "id"}) {
    SCOPED_TRACE(formulation);
    Task task = load_task(kPandaHandCircle);
    task.formulation = formulation;
    mj::TaskRun run(task);
    const VecX<double> lower = run.torque_lower(), upper = run.torque_upper();
    double beyond = -1;
    const mj::RunResult r = run.run([&](const mj::StepRecord& step) {
      beyond = std::max(beyond, std::max((step.u - upper).maxCoeff(), (lower - step.u).maxCoeff()));
    });
    ASSERT_FALSE(r.diverged) << r.divergence_reason;
    ASSERT_TRUE(r.tracking.has_value());
    EXPECT_LT(r.tracking->position_rms, 5e-3);
    EXPECT_LE(beyond, 0.0) << "the plant received a torque beyond its actuator's range";
    EXPECT_NEAR(run.plant().full_q()[7], 0.04, 1e-3);
  }
}

}  // namespace
}  // namespace idmpc
