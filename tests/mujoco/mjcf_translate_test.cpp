// MJCF written for MuJoCo >= 2.3 loads in this build's MuJoCo 2.2: each translation gives the
// mjModel values MuJoCo >= 2.3 computes (expected values worked out by hand from the numbers in
// the fixtures, tests/mujoco/fixtures), the notice lists every translation, what cannot be
// translated is listed all at once in one error line, and the user's files are left unchanged.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/gravcomp.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

const std::string kFixtures = IDMPC_SOURCE_DIR "/tests/mujoco/fixtures/";
// numbers MuJoCo's compiler carries through a few operations (ranges, inertia sums)
constexpr double kTight = 1e-12;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

std::string joined(const std::vector<mj::Translation>& translations) {
  std::string out;
  for (const mj::Translation& t : translations) out += "\n  " + t.kind + ": " + t.text;
  return out;
}

int actuator(const mjModel* m, const char* name) {
  const int u = mj_name2id(m, mjOBJ_ACTUATOR, name);
  EXPECT_GE(u, 0) << name;
  return u;
}

int joint(const mjModel* m, const char* name) {
  const int j = mj_name2id(m, mjOBJ_JOINT, name);
  EXPECT_GE(j, 0) << name;
  return j;
}

// exactly one translation line contains `part`
void expect_one_notice(const mj::LoadedModel& loaded, const std::string& part) {
  int count = 0;
  for (const mj::Translation& t : loaded.translations) count += t.text.find(part) != std::string::npos;
  EXPECT_EQ(count, 1) << "'" << part << "' in:" << joined(loaded.translations);
}

class MjcfTranslate : public ::testing::Test {
 protected:
  void SetUp() override {
    mj::install_error_handlers();
    mj::take_warnings();
    dir_ = ::testing::TempDir() + "idmpc_translate_test_" + std::to_string(::getpid()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "/";
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    fs::remove_all(dir_);
    const std::vector<std::string> warnings = mj::take_warnings();
    EXPECT_TRUE(warnings.empty()) << "MuJoCo warnings:" << joined(warnings);
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ + name, std::ios::binary) << text;
    return dir_ + name;
  }
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

// fr3_translate.xml: positions with kp/kv on the element and in a class, inheritrange from a
// class and on an element, actuatorfrcrange with a gear and with a forcerange, implicitfast,
// ranges without limited, a keyframe with a trailing blank
void expect_fr3_translated(const mj::LoadedModel& loaded) {
  const mjModel* m = loaded.model.get();
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(m->nu, 3);
  EXPECT_EQ(m->opt.integrator, mjINT_IMPLICIT);
  for (int j = 0; j < m->njnt; ++j) EXPECT_TRUE(m->jnt_limited[j]) << "joint " << j;
  const int a1 = actuator(m, "fr3_joint1"), a2 = actuator(m, "fr3_joint2"), a4 = actuator(m, "fr3_joint4");
  // kp/kv → gain kp, bias (0, −kp, −kv); fr3_joint4's kp 2000, kv 200 come from class fr3_wrist
  for (const auto& [u, kp, kv] : {std::make_tuple(a1, 4500.0, 450.0), std::make_tuple(a2, 4500.0, 450.0),
                                  std::make_tuple(a4, 2000.0, 200.0)}) {
    SCOPED_TRACE("actuator " + std::to_string(u));
    EXPECT_EQ(m->actuator_gainprm[u * mjNGAIN], kp);
    EXPECT_EQ(m->actuator_biasprm[u * mjNBIAS + 0], 0.0);
    EXPECT_EQ(m->actuator_biasprm[u * mjNBIAS + 1], -kp);
    EXPECT_EQ(m->actuator_biasprm[u * mjNBIAS + 2], -kv);
    EXPECT_TRUE(m->actuator_ctrllimited[u]);
    EXPECT_TRUE(m->actuator_forcelimited[u]);
  }
  // inheritrange 1 (class fr3): the joint range; 0.8 on fr3_joint2: ±0.8 × 1.8361 about 0
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a1], -2.9007, kTight);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a1 + 1], 2.9007, kTight);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a2], -1.46888, kTight);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a2 + 1], 1.46888, kTight);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a4], -3.0770, kTight);
  EXPECT_NEAR(m->actuator_ctrlrange[2 * a4 + 1], -0.1169, kTight);
  // actuatorfrcrange ±87 through gear 1 and gear 2; ±12 meets class fr3_wrist's forcerange ±10
  EXPECT_EQ(m->actuator_forcerange[2 * a1], -87);
  EXPECT_EQ(m->actuator_forcerange[2 * a1 + 1], 87);
  EXPECT_EQ(m->actuator_forcerange[2 * a2], -43.5);
  EXPECT_EQ(m->actuator_forcerange[2 * a2 + 1], 43.5);
  EXPECT_EQ(m->actuator_forcerange[2 * a4], -10);
  EXPECT_EQ(m->actuator_forcerange[2 * a4 + 1], 10);
  // every joint's range went to its actuator: none is left for the caller
  for (int j = 0; j < m->njnt; ++j) {
    EXPECT_TRUE(std::isinf(loaded.joint_force_lower.at(j)) && std::isinf(loaded.joint_force_upper.at(j)));
  }
  // the keyframe without its trailing blank
  ASSERT_EQ(m->nkey, 1);
  EXPECT_EQ(m->key_qpos[2], -1.57079);
  // joint damping and armature through childclass
  EXPECT_EQ(m->dof_damping[2], 0.21);
  EXPECT_EQ(m->dof_armature[2], 0.195);
}

TEST_F(MjcfTranslate, Fr3GetsMujoco3ServoGainsRangesAndForceLimits) {
  const mj::LoadedModel loaded = mj::load_model_translated(kFixtures + "fr3_translate.xml");
  expect_fr3_translated(loaded);
  // one notice line per translation
  EXPECT_EQ(loaded.translations.size(), 12u) << joined(loaded.translations);
  expect_one_notice(loaded, "<compiler autolimits> set to true, MuJoCo >= 3.0.0's default (earlier versions' is false)");
  expect_one_notice(loaded, "integrator implicitfast replaced by implicit");
  expect_one_notice(loaded, "keyframe qpos trimmed");
  expect_one_notice(loaded, "actuator 'fr3_joint1' (<position> 'fr3_joint1', line 50): kv 450 gives biasprm[2] = -450");
  expect_one_notice(loaded, "actuator 'fr3_joint4' (<position> 'fr3_joint4', line 52): kv 200 (class 'fr3_wrist'");
  expect_one_notice(loaded, "inheritrange 0.8 gives ctrlrange [-1.46888, 1.46888]");
  expect_one_notice(loaded, "actuatorfrcrange [-87, 87] becomes forcerange [-43.5, 43.5] of actuator 'fr3_joint2'");
  expect_one_notice(loaded, "actuatorfrcrange [-12, 12] becomes forcerange [-10, 10] (its part within the actuator's own)");
  const std::string notice = loaded.notice();
  EXPECT_NE(notice.find("fr3_translate.xml' is written for a newer MuJoCo"), std::string::npos) << notice;
  EXPECT_NE(notice.find(": 12 changes (autolimits, implicitfast as implicit, keyframe blanks, inheritrange ×3, kv ×3, "
                        "actuatorfrcrange ×3), each listed by 'idmpc check'"),
            std::string::npos)
      << notice;
  EXPECT_EQ(notice.find('\n'), std::string::npos) << notice;
}

TEST_F(MjcfTranslate, IncludedFilesAreTranslatedToo) {
  const mj::LoadedModel loaded = mj::load_model_translated(kFixtures + "fr3_scene.xml");
  expect_fr3_translated(loaded);
  EXPECT_EQ(loaded.model->ngeom, 4);  // the arm's three and the floor
  // included lines are named with their file
  expect_one_notice(loaded, "fr3_translate.xml line 50): kv 450");
}

TEST_F(MjcfTranslate, TheUsersFilesAreLeftByteIdentical) {
  const std::vector<std::string> files = {"fr3_scene.xml", "fr3_translate.xml", "so_arm100_translate.xml",
                                          "mesh_arm.xml", "meshes/tetra.obj"};
  // every entry of the fixtures' directory, files and folders
  auto listing = [] {
    std::set<std::string> entries;
    for (const auto& e : fs::recursive_directory_iterator(kFixtures)) entries.insert(e.path().string());
    return entries;
  };
  const std::set<std::string> entries_before = listing();
  std::vector<std::string> before;
  for (const std::string& f : files) before.push_back(slurp(kFixtures + f));
  for (const char* model : {"fr3_scene.xml", "so_arm100_translate.xml", "mesh_arm.xml"}) {
    mj::load_model_translated(kFixtures + model);
  }
  for (std::size_t k = 0; k < files.size(); ++k) EXPECT_EQ(slurp(kFixtures + files[k]), before[k]) << files[k];
  // and nothing was added next to them
  EXPECT_EQ(listing(), entries_before);
}

TEST_F(MjcfTranslate, DampratioGivesKvFromTheInertiaAtQpos0) {
  const mj::LoadedModel loaded = mj::load_model_translated(kFixtures + "so_arm100_translate.xml");
  const mjModel* m = loaded.model.get();
  const int pitch = actuator(m, "Wrist_Pitch"), roll = actuator(m, "Wrist_Roll");
  // Wrist_Roll (axis y) carries Fixed_Jaw, its centre of mass on the axis: I_yy + armature,
  // reflected through gear 2
  const double roll_mass = (4.6e-05 + 0.1) / (2.0 * 2.0);
  // Wrist_Pitch (axis x) carries both bodies; Fixed_Jaw's centre of mass is 0.0601 + 0.03 off it
  const double pitch_mass = 0.1 + 3.45e-05 + 5.0e-05 + 0.0929859 * 0.0901 * 0.0901;
  // kv = dampratio · 2 · √(kp · m), dampratio 1, kp 50 (class so_arm100)
  EXPECT_NEAR(m->actuator_biasprm[roll * mjNBIAS + 2], -2 * std::sqrt(50 * roll_mass), kTight);
  EXPECT_NEAR(m->actuator_biasprm[pitch * mjNBIAS + 2], -2 * std::sqrt(50 * pitch_mass), kTight);
  EXPECT_EQ(m->actuator_biasprm[pitch * mjNBIAS + 1], -50);
  // ranges without their limited flags (autolimits)
  for (const int u : {pitch, roll}) {
    EXPECT_TRUE(m->actuator_ctrllimited[u]);
    EXPECT_TRUE(m->actuator_forcelimited[u]);
    EXPECT_EQ(m->actuator_forcerange[2 * u + 1], 35);
  }
  EXPECT_TRUE(m->jnt_limited[joint(m, "Wrist_Pitch")]);
  EXPECT_EQ(m->jnt_range[2 * joint(m, "Wrist_Roll")], -3.14158);
  EXPECT_EQ(m->opt.integrator, mjINT_EULER);
  expect_one_notice(loaded, "dampratio 1 (class 'Wrist_Roll'");
  expect_one_notice(loaded, "<compiler autolimits> set to true");
  EXPECT_EQ(loaded.translations.size(), 3u) << joined(loaded.translations);
  // the one-line notice names them by kind: dampratio, though its line gives a kv
  EXPECT_NE(loaded.notice().find(": 3 changes (autolimits, dampratio ×2), each listed by 'idmpc check'"),
            std::string::npos)
      << loaded.notice();
}

TEST_F(MjcfTranslate, ServosOfATranslatedArmBecomeJointTorquesWithItsLimits) {
  const mj::LoadedModel loaded = mj::load_model_translated(kFixtures + "fr3_translate.xml");
  mj::ImportOptions options;
  options.joint_force_lower = loaded.joint_force_lower;
  options.joint_force_upper = loaded.joint_force_upper;
  const mj::ImportedModel imported = mj::import_model(loaded.model.get(), "fr3", options);
  const mj::Actuation& act = imported.actuation;
  EXPECT_TRUE(act.direct);
  EXPECT_EQ(act.replaced_servos, (std::vector<std::string>{"fr3_joint1", "fr3_joint2", "fr3_joint4"}));
  // forcerange × gear: the actuatorfrcrange of each joint (±10 where the class's forcerange is
  // tighter)
  EXPECT_EQ(act.torque_lower, (VecX<double>(3) << -87, -87, -10).finished());
  EXPECT_EQ(act.torque_upper, (VecX<double>(3) << 87, 87, 10).finished());
  EXPECT_TRUE(act.unbounded_joints.empty());
  ASSERT_EQ(imported.notices.size(), 1u) << joined(imported.notices);
  EXPECT_NE(imported.notices[0].find("position servos 'fr3_joint1', 'fr3_joint2', 'fr3_joint4' replaced by joint "
                                     "torques"),
            std::string::npos)
      << imported.notices[0];
}

TEST_F(MjcfTranslate, ActuatorForceRangeOfAJointWithoutActuatorIsKeptForTheCaller) {
  // the shoulder's range comes from the class its body gives its children, the elbow's is its own
  const std::string path = write("bare.xml", R"(<mujoco>
  <default><default class="arm"><joint actuatorfrcrange="-3 4"/></default></default>
  <worldbody>
    <body name="upper" pos="0 0 1" childclass="arm">
      <joint name="shoulder" axis="0 1 0"/>
      <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
      <body name="fore" pos="0.3 0 0">
        <joint name="elbow" axis="0 1 0" actuatorfrcrange="-1 2"/>
        <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  const mj::LoadedModel loaded = mj::load_model_translated(path);
  EXPECT_EQ(loaded.joint_force_lower, (std::vector<double>{-3, -1}));
  EXPECT_EQ(loaded.joint_force_upper, (std::vector<double>{4, 2}));
  expect_one_notice(loaded, "joint 'shoulder' (<joint> 'shoulder', line 5): actuatorfrcrange [-3, 4] kept as the "
                            "joint's torque range (no actuator drives it)");
  mj::ImportOptions options;
  options.joint_force_lower = loaded.joint_force_lower;
  options.joint_force_upper = loaded.joint_force_upper;
  const mj::ImportedModel imported = mj::import_model(loaded.model.get(), path, options);
  EXPECT_EQ(imported.actuation.torque_lower, (VecX<double>(2) << -3, -1).finished());
  EXPECT_EQ(imported.actuation.torque_upper, (VecX<double>(2) << 4, 2).finished());
}

// MuJoCo's class rule for an element without its own class: the childclass of the nearest
// enclosing body that has one, not of an outer body; an element's own class wins over any
TEST_F(MjcfTranslate, ChildclassIsTheNearestEnclosingBodys) {
  const std::string path = write("nested.xml", R"(<mujoco>
  <default>
    <default class="outer"><joint actuatorfrcrange="-3 4"/></default>
    <default class="inner"><joint actuatorfrcrange="-1 2"/></default>
  </default>
  <worldbody>
    <body name="upper" pos="0 0 1" childclass="outer">
      <joint name="shoulder" axis="0 1 0"/>
      <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
      <body name="fore" pos="0.3 0 0" childclass="inner">
        <joint name="elbow" axis="0 1 0"/>
        <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
        <body name="hand" pos="0.3 0 0">
          <joint name="wrist" axis="0 1 0"/>
          <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
          <body name="finger" pos="0.1 0 0">
            <joint name="knuckle" axis="0 1 0" class="outer"/>
            <geom type="sphere" size="0.05" mass="0.1" contype="0" conaffinity="0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  const mj::LoadedModel loaded = mj::load_model_translated(path);
  // shoulder: its body's class; elbow: its own body's, nearer than the outer one; wrist: the
  // nearest enclosing body with a childclass (fore), not upper; knuckle: its own class
  EXPECT_EQ(loaded.joint_force_lower, (std::vector<double>{-3, -1, -1, -3}));
  EXPECT_EQ(loaded.joint_force_upper, (std::vector<double>{4, 2, 2, 4}));
}

TEST_F(MjcfTranslate, WhatCannotBeTranslatedIsListedAllAtOnceInOneLine) {
  const std::string path = write("newer.xml", R"(<mujoco>
  <option><flag eulerdamp="disable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 1" gravcomp="1">
      <joint name="shoulder" axis="0 1 0" actuatorgravcomp="true" actuatorfrcrange="-5 5"/>
      <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
      <frame name="tool">
        <body name="fore"><geom type="sphere" size="0.1" mass="1"/></body>
      </frame>
      <body name="hand" pos="0.3 0 0">
        <joint name="wrist" axis="0 1 0" actuatorfrcrange="-2 2"/>
        <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="both"><joint joint="shoulder" coef="1"/><joint joint="wrist" coef="0.5"/></fixed></tendon>
  <actuator>
    <motor name="m1" joint="shoulder"/><motor name="m2" joint="shoulder"/><motor name="pull" tendon="both"/>
  </actuator>
</mujoco>)");
  const std::string message = load_error(path);
  for (const std::string& part :
       {"cannot load model '" + path + "'", std::string("needs a newer MuJoCo"), "this build uses MuJoCo " +
        std::string(mj_versionString()), std::string("5 items"),
        std::string("attribute 'eulerdamp' (<flag>, line 2)"),
        std::string("attribute 'actuatorgravcomp' (<joint> 'shoulder', line 5): with the joint's actuatorfrcrange"),
        std::string("element <frame> 'tool', line 7"),
        std::string("attribute 'actuatorfrcrange' (<joint> 'shoulder', line 5): it clamps the sum of the forces of "
                    "actuator 'm1', actuator 'm2', actuator 'pull'"),
        std::string("attribute 'actuatorfrcrange' (<joint> 'wrist', line 11): it clamps the sum of the forces of "
                    "actuator 'pull'")}) {
    EXPECT_NE(message.find(part), std::string::npos) << "lacks '" << part << "': " << message;
  }
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_EQ(message.find("attribute 'gravcomp'"), std::string::npos) << "gravcomp is translated: " << message;
}

// MuJoCo >= 2.3 applies −c·m·g at each body's centre of mass: with the same c on every body,
// the passive force is c times the gravity torques MuJoCo computes itself (qfrc_bias at rest)
TEST_F(MjcfTranslate, GravcompIsThePassiveForceMuJoCo23Applies) {
  for (const double c : {1.0, 0.4}) {
    const std::string gc = std::to_string(c);
    const std::string path = write("gravcomp.xml", R"(<mujoco>
  <worldbody>
    <body name="upper" pos="0 0 1" gravcomp=")" + gc + R"(">
      <joint name="shoulder" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.05" mass="1.3" contype="0" conaffinity="0"/>
      <body name="fore" pos="0.3 0 0.1" gravcomp=")" + gc + R"(">
        <joint name="elbow" axis="1 0 0" actuatorgravcomp="true"/>
        <geom type="box" pos="0.1 0.05 0" size="0.1 0.03 0.02" mass="0.7" contype="0" conaffinity="0"/>
        <body name="tool" pos="0.2 0 0" gravcomp=")" + gc + R"(">
          <geom type="sphere" pos="0 0.04 0" size="0.03" mass="0.2" contype="0" conaffinity="0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)");
    const mj::LoadedModel loaded = mj::load_model_translated(path);
    const mjModel* m = loaded.model.get();
    EXPECT_EQ(mj::body_gravcomp(m), (std::vector<double>{0, c, c, c}));
    expect_one_notice(loaded, "gravcomp on 3 bodies (<body> 'upper', line 3, …) applied as MuJoCo >= 2.3");
    expect_one_notice(loaded, "actuatorgravcomp (<joint> 'elbow', line 7) is the same force without actuatorfrcrange");
    const mj::DataPtr d = mj::make_data(m);
    d->qpos[0] = 0.7;
    d->qpos[1] = -1.1;
    mj_forward(m, d.get());
    for (int i = 0; i < m->nv; ++i) {
      EXPECT_NEAR(d->qfrc_passive[i], c * d->qfrc_bias[i], 1e-12) << "dof " << i << ", gravcomp " << c;
    }
    EXPECT_GT(std::abs(d->qfrc_bias[0]), 1.0);
  }
}

TEST_F(MjcfTranslate, NoOpValuesAreDroppedAndSaidSo) {
  const std::string path = write("noop.xml", R"(<mujoco>
  <compiler assetdir="."/>
  <option><flag eulerdamp="enable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 1" gravcomp="0">
      <joint name="shoulder" axis="0 1 0" actuatorgravcomp="false"/>
      <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
      <camera name="eye" resolution="640 480" focal="0.01 0.01" sensorsize="0.01 0.01"/>
      <camera name="side" focal="0.02 0.02" orthographic="false"/>
      <light name="lamp" type="directional" intensity="2"/>
    </body>
  </worldbody>
</mujoco>)");
  const mj::LoadedModel loaded = mj::load_model_translated(path);
  EXPECT_EQ(loaded.model->njnt, 1);
  EXPECT_EQ(loaded.model->ncam, 2);
  EXPECT_EQ(loaded.model->light_directional[0], 1) << "a directional light stays directional";
  for (const std::string part : {"gravcomp=\"0\" dropped", "actuatorgravcomp=\"false\" dropped",
                                 "eulerdamp=\"enable\" dropped",
                                 "dropped what MuJoCo 2.2 does not have and only rendering uses: camera focal (2×), "
                                 "camera orthographic, camera resolution, camera sensorsize, light intensity, light type",
                                 "<compiler assetdir=\".\"> given as meshdir and texturedir"}) {
    expect_one_notice(loaded, part);
  }
}

TEST_F(MjcfTranslate, AFileThatNeedsNoTranslationLoadsAsWritten) {
  const std::string path = write("plain.xml", R"(<mujoco>
  <compiler autolimits="false"/>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="shoulder" axis="0 1 0" limited="true" range="-1 1"/>
      <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator><position name="servo" joint="shoulder" kp="10"/></actuator>
</mujoco>)");
  const mj::LoadedModel loaded = mj::load_model_translated(path);
  EXPECT_TRUE(loaded.translations.empty()) << joined(loaded.translations);
  EXPECT_EQ(loaded.notice(), "");
  // MuJoCo 2.2's own rule stands where the file sets autolimits: no flag, no limit
  const std::string message = load_error(write("strict.xml", R"(<mujoco>
  <compiler autolimits="false"/>
  <worldbody><body><joint name="j" range="-1 1"/><geom size="0.1" mass="1"/></body></worldbody>
</mujoco>)"));
  EXPECT_NE(message.find("joint has `range` but not `limited`"), std::string::npos) << message;
}

TEST_F(MjcfTranslate, MeshesOfATranslatedModelLoadFromDiskAndAMissingOneIsNamed) {
  const mj::LoadedModel loaded = mj::load_model_translated(kFixtures + "mesh_arm.xml");
  ASSERT_EQ(loaded.model->nmesh, 1);
  EXPECT_EQ(loaded.model->mesh_facenum[0], 4);  // the tetrahedron of meshes/tetra.obj
  EXPECT_EQ(loaded.model->opt.integrator, mjINT_IMPLICIT);
  // the same model where its mesh file is missing
  std::string xml = slurp(kFixtures + "mesh_arm.xml");
  const std::string path = write("mesh_arm.xml", xml);
  std::string message = load_error(path);
  EXPECT_NE(message.find("mesh file '" + dir_ + "meshes/tetra.obj' does not exist"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  // named where MuJoCo >= 2.3's assetdir puts it
  xml.replace(xml.find(R"(meshdir="meshes")"), 16, R"(assetdir="assets")");
  message = load_error(write("assetdir.xml", xml));
  EXPECT_NE(message.find("mesh file '" + dir_ + "assets/tetra.obj' does not exist"), std::string::npos) << message;
}

TEST_F(MjcfTranslate, MujocosOwnMessagesNameTheUsersLines) {
  // translated (implicitfast), with an error MuJoCo finds on line 6
  const std::string path = write("bad.xml", R"(<mujoco>
  <option integrator="implicitfast"/>
  <worldbody>
    <body name="arm"
          pos="0 0 1">
      <joint name="shoulder" type="bogus"/>
      <geom type="sphere" size="0.1" mass="1"/>
    </body>
  </worldbody>
</mujoco>)");
  const std::string message = load_error(path);
  EXPECT_NE(message.find("line 6"), std::string::npos) << message;
}

}  // namespace
}  // namespace idmpc
