// The public entry points: a controller built from a model and settings (limits given once, the
// models shared, the target settable between updates) and mj::TaskRun, which makes a task file a
// plant and a controller exactly as `idmpc swingup` runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/mujoco/task_run.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";

ControllerSettings arm4_settings(int n) {
  ControllerSettings s;
  s.weights = test::paper_weights(n);
  s.q_ref = VecX<double>::Zero(n);
  s.cgmres.alpha = 0;  // a full horizon from the start
  s.cgmres.init_full_horizon = true;
  return s;
}

// the model given to the controller may go out of scope: the controller shares it (the
// sanitizer build sees a dangling one)
TEST(ControllerSettings, TheControllerSharesItsModel) {
  std::unique_ptr<Controller> c;
  {
    auto model = std::make_shared<const Model>(test::load_problem(kArm4).model);
    c = std::make_unique<Controller>(model, arm4_settings(4));
  }
  const VecX<double> q = VecX<double>::Constant(4, 0.05), v = VecX<double>::Zero(4);
  c->initialize(q, v);
  ASSERT_EQ(c->failure(), "");
  EXPECT_TRUE(c->update(1e-3, q, v)) << c->failure();
  EXPECT_TRUE(c->torque().allFinite());
}

// one set of limits: the horizon's constraints on every bounded joint and the clamp of the
// returned torque; a clamp beyond the horizon's bounds is refused, naming the joint, a tighter
// one taken
TEST(ControllerSettings, LimitsAreGivenOnceForTheHorizonAndTheClamp) {
  auto model = std::make_shared<const Model>(test::load_problem(kArm4).model);
  ControllerSettings s = arm4_settings(4);
  s.torque_lower = VecX<double>::Constant(4, -20);
  s.torque_upper = VecX<double>::Constant(4, 20);
  s.torque_upper[3] = std::numeric_limits<double>::infinity();
  s.torque_lower[3] = -std::numeric_limits<double>::infinity();
  Controller c(model, s);
  EXPECT_EQ(c.problem().m(), 3) << "joints 0-2 bounded, joint 3 not";
  EXPECT_EQ(c.torque_lower(), s.torque_lower);
  EXPECT_EQ(c.torque_upper(), s.torque_upper);
  VecX<double> other = s.torque_upper;
  other[1] = 30;
  try {
    c.set_torque_limits(s.torque_lower, other);
    FAIL() << "a clamp beyond the horizon's bounds was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'joint1'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("horizon"), std::string::npos) << e.what();
  }
  // a tighter clamp is taken (an actuator derated while running), and every torque respects it
  VecX<double> tighter = s.torque_upper;
  tighter[1] = 5;
  c.set_torque_limits(s.torque_lower, tighter);
  EXPECT_EQ(c.torque_upper()[1], 5);
  VecX<double> q = VecX<double>::Zero(4);
  q[0] = -M_PI;
  c.initialize(q, VecX<double>::Zero(4));
  for (int k = 1; k <= 20; ++k) {
    ASSERT_TRUE(c.update(k * c.dt(), q, VecX<double>::Zero(4))) << c.failure();
    EXPECT_LE(c.torque()[1], 5.0);
  }
  // the unconstrained horizon keeps the clamp only
  s.limits_in_horizon = false;
  Controller clamp_only(model, s);
  EXPECT_EQ(clamp_only.problem().m(), 0);
  EXPECT_EQ(clamp_only.torque_upper(), s.torque_upper);
  // sizes are checked by name
  s.q_ref = VecX<double>::Zero(3);
  EXPECT_THROW(
      {
        try {
          Controller bad(model, s);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("q_ref has 3 entries"), std::string::npos) << e.what();
          throw;
        }
      },
      std::invalid_argument);
}

// the target moves between updates: the arm, held at the first target, goes to the second
TEST(ControllerSettings, TheTargetChangesBetweenUpdates) {
  Task task = paper_task();
  task.model = kArm4;
  task.q0.assign(4, 0.0);
  task.q0_rule.clear();
  task.alpha = 0;
  task.init_full_horizon = true;
  mj::TaskRun run(task);
  Controller& c = run.controller();
  mj::Plant& plant = run.plant();
  VecX<double> target = VecX<double>::Zero(4);
  plant.reset(target, VecX<double>::Zero(4));
  std::string reason;
  c.initialize(plant.q(), plant.v());
  const VecX<double> second = (VecX<double>(4) << 0.3, -0.2, 0.1, 0.2).finished();
  const int steps = static_cast<int>(std::lround(2.5 / c.dt()));
  for (int k = 0; k < steps; ++k) {
    ASSERT_TRUE(plant.step(c.torque(), &reason)) << reason;
    if (k == 500) {
      EXPECT_LT(plant.q().cwiseAbs().maxCoeff(), 1e-3) << "held at the first target";
      c.set_target(second);
      EXPECT_EQ(c.q_ref(), second);
    }
    ASSERT_TRUE(c.update((k + 1) * c.dt(), plant.q(), plant.v())) << c.failure();
  }
  EXPECT_LT((plant.q() - second).cwiseAbs().maxCoeff(), 2e-2) << "at the second target";
  EXPECT_THROW(c.set_target(VecX<double>::Zero(3)), std::invalid_argument);
  VecX<double> nan_target = second;
  nan_target[2] = std::nan("");
  EXPECT_THROW(c.set_target(nan_target), std::invalid_argument);
}

// a task file becomes the same run as `idmpc swingup` makes of it: what it changed and chose is
// said before it runs; bad values name their field
TEST(TaskRun, SaysWhatItDidBeforeRunningAndRunsTheTask) {
  Task task = load_task(IDMPC_SOURCE_DIR "/mjcf/lite6_reach.json");  // position servos
  task.duration = 0.05;
  task.solver = "cgmres";  // its start's residual below is C/GMRES's F
  mj::TaskRun run(task);
  EXPECT_EQ(run.n(), 6);
  bool servos = false, auto_weights = false;
  for (const auto& s : run.notices()) {
    servos = servos || s.find("servos") != std::string::npos;
    auto_weights = auto_weights || s.find("weights \"auto\"") != std::string::npos;
  }
  EXPECT_TRUE(servos && auto_weights);
  EXPECT_EQ(run.horizon().weights.R.size(), 6);
  EXPECT_GT(run.controller().disturbance_observer(), 0) << "offset-free by default on real arms";
  EXPECT_EQ(run.controller().problem().m(), 6);
  int rows = 0;
  const mj::RunResult r = run.run([&](const mj::StepRecord&) { ++rows; });
  EXPECT_FALSE(r.diverged) << r.divergence_reason;
  EXPECT_EQ(rows, r.steps);
  EXPECT_EQ(r.steps, 50);
  const RunSummary s = run.summary(r);
  EXPECT_EQ(s.steps, r.steps);
  EXPECT_EQ(s.final_q_error, r.final_q_error);
  EXPECT_EQ(s.R.size(), 6u);
  EXPECT_GT(run.horizon().open_loop_rate, 0.0) << "an arm under gravity";
  EXPECT_EQ(s.open_loop_rate, run.horizon().open_loop_rate);

  // the start was solved: no warning; the controller keeps its residual
  EXPECT_EQ(run.controller().start_residual(), r.init_residual);
  EXPECT_LE(r.init_residual, kStartSolved);
  for (const std::string& w : s.warnings) EXPECT_EQ(w.find("the start was not solved"), std::string::npos) << w;
  // a start left above kStartSolved is a warning of the run, said with its residual
  EXPECT_EQ(run.start_warning(0.5 * kStartSolved), "");
  EXPECT_EQ(run.start_warning(std::nan("")), "");
  EXPECT_NE(run.start_warning(47.4).find("the start was not solved: |F| = 47.4"), std::string::npos);
  mj::RunResult unsolved = r;
  unsolved.init_residual = 47.4;
  const std::vector<std::string> warned = run.summary(unsolved).warnings;
  EXPECT_EQ(std::count_if(warned.begin(), warned.end(),
                          [](const std::string& w) { return w.rfind("the start was not solved", 0) == 0; }),
            1);
  // the Riccati solver's start is its own (its residual is not C/GMRES's F)
  Task riccati = task;
  riccati.solver = "riccati";
  EXPECT_EQ(mj::TaskRun(riccati).start_warning(47.4), "");

  task.qref = {0.1, 0.2};
  try {
    mj::TaskRun bad(task);
    FAIL() << "a qref of 2 values on 6 joints was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("qref"), std::string::npos) << e.what();
  }
}

// One settings type: a Controller built by hand from the run's settings and model makes the same
// automatic choices (smoothed friction, implicit damping, weights) and drives the plant exactly
// as the run's own, under both solver families, with a frame target on a moving reference
TEST(TaskRun, AControllerBuiltFromItsSettingsIsTheOneItRuns) {
  for (const auto& [file, solver] : {std::pair{"xarm7_circle.json", "cgmres"}, std::pair{"fr3_reach.json", "riccati"}}) {
    SCOPED_TRACE(file);
    Task task = load_task(std::string(IDMPC_SOURCE_DIR "/mjcf/") + file);
    task.duration = 0.05;
    task.solver = solver;
    mj::TaskRun run(task);
    const ControllerSettings& settings = run.settings();
    ASSERT_GT(settings.friction_loss.maxCoeff(), 0.0) << "an arm with friction loss, else the case proves little";
    ASSERT_GT(settings.plant_step, 0.0);
    ASSERT_FALSE(run.horizon().notes.empty()) << "choices made automatically, else the case proves little";
    std::vector<VecX<double>> by_run, by_hand;
    const mj::RunResult r = run.run([&](const mj::StepRecord& s) { by_run.push_back(s.u); });
    ASSERT_FALSE(r.diverged) << r.divergence_reason;

    Controller controller(run.shared_model(), settings);
    const HorizonSetup& chosen = *controller.horizon_setup();
    EXPECT_EQ(chosen.notes, run.horizon().notes);
    EXPECT_EQ(chosen.weights.R, run.horizon().weights.R);
    EXPECT_EQ(chosen.friction_velocity, run.horizon().friction_velocity);
    mj::Plant plant(run.mj_model(), run.imported().actuation);
    const mj::RunResult h =
        mj::run_closed_loop(plant, controller, run.loop_settings(), [&](const mj::StepRecord& s) { by_hand.push_back(s.u); });
    ASSERT_FALSE(h.diverged) << h.divergence_reason;
    ASSERT_EQ(by_hand.size(), by_run.size());
    for (size_t k = 0; k < by_run.size(); ++k) EXPECT_EQ(by_hand[k], by_run[k]) << "step " << k;
  }
}

// Solver "auto", a task's default (horizon_setup.hpp): the run's controller is the solver its
// setup chose (the Riccati recursion on a real arm, C/GMRES on the cart-pole), the same in both
// formulations, and its task and summary record that one, so that the task as run can be run
// again (not run here: the Python suite runs these tasks)
TEST(TaskRun, AutoSolverIsChosenOnceAndRecorded) {
  for (const auto& [file, expected] :
       {std::pair{"ur5e_reach.json", "riccati"}, std::pair{"cartpole_swingup.json", "cgmres"}}) {
    const Task task = load_task(std::string(IDMPC_SOURCE_DIR "/mjcf/") + file);
    ASSERT_EQ(task.solver, "auto") << file << ": the case needs the default";
    for (const char* formulation : {"fd", "id"}) {
      SCOPED_TRACE(std::string(file) + " " + formulation);
      Task t = task;
      t.formulation = formulation;
      mj::TaskRun run(t);
      EXPECT_EQ(to_string(run.controller().solver_kind()), expected);
      EXPECT_EQ(to_string(run.settings().solver), expected);
      EXPECT_EQ(run.task().solver, expected);
      const RunSummary s = run.summary(mj::RunResult{});
      EXPECT_EQ(s.task.solver, expected);
      EXPECT_EQ(to_json(s.task).at("solver"), expected) << "the task as run names it";
    }
  }
}

// The Riccati solver's start on a fast unstable arm (tests/mujoco/fixtures/fast_open_loop_arm.xml:
// λ = 30 1/s, R up to 2e6): at its initial guess the KKT residual exceeds 1e8 (the costates
// through 25 unstable stages), which is no divergence while the iterates stay bounded; the
// globalized iterations bring it to about 40 and the loop runs (its 6 s task reaches, 6e-4 rad)
TEST(TaskRun, TheRiccatiStartIsNotStoppedByALargeInitialResidual) {
  Task task = load_task(IDMPC_SOURCE_DIR "/tests/mujoco/fixtures/fast_open_loop_arm.json");
  task.formulation = "fd";
  task.duration = 0.01;
  {
    // the case: the residual at the initial guess (a start of no iterations)
    Task guess = task;
    guess.riccati.init_iterations = 0;
    mj::TaskRun at_guess(guess);
    at_guess.controller().initialize(at_guess.settings().q_start, VecX<double>::Zero(at_guess.n()));
    ASSERT_GT(at_guess.controller().start_residual(), 1e8) << "the case needs a large initial residual";
  }
  mj::TaskRun run(task);
  ASSERT_EQ(to_string(run.controller().solver_kind()), "riccati");
  ASSERT_GT(run.horizon().open_loop_rate, 20.0) << "the case needs a fast open loop";
  const mj::RunResult r = run.run();
  EXPECT_FALSE(r.diverged) << r.divergence_reason << " at " << r.diverged_at;
  EXPECT_LT(r.init_residual, 1e3);
  EXPECT_EQ(r.steps, 10);
}

// a task from JSON text, as if read from `name` in the shipped mjcf/ directory
Task task_in_mjcf(const std::string& json, const std::string& name = "t.json") {
  Task t = task_from_json(nlohmann::json::parse(json), "task file '" + name + "'", arm_defaults());
  t.source = std::string(IDMPC_SOURCE_DIR "/mjcf/") + name;
  t.model = std::string(IDMPC_SOURCE_DIR "/mjcf/") + t.model;
  return t;
}

std::string error_of(const std::string& json) {
  try {
    const mj::TaskRun run(task_in_mjcf(json));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

// a bad frame target or reference is one line naming the task file and the field
TEST(TaskRun, FrameTargetAndReferenceErrorsNameTheField) {
  const std::string where = std::string("task file '" IDMPC_SOURCE_DIR "/mjcf/t.json'");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "target": {"frame": "nope"}})"),
            "model '" IDMPC_SOURCE_DIR "/mjcf/ur5e.xml' has no site or body 'nope' (sites: tip)");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "target": {"frame": "tip", "orientation": [1, 1, 0, 0]}})"),
            "target.orientation [w, x, y, z] must be a unit quaternion, its norm is 1.41421");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "target": {"frame": "tip", "weights": {"orientation": -1}}})"),
            "target.weights (position, orientation) must be finite and non-negative, got -1.000000");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "target": {"frame": "tip"}, "reference": {"shape": "circle"}})"),
            where + ", 'reference': missing field 'radius' (a positive number [m])");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "reference": {"shape": "line", "to": [1, 2], "duration": 1}})"),
            where + ", 'reference': field 'to': expected a list of 6 numbers (the reference's dim), got [1,2]");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "target": {"frame": "tip"}, "tracking_tolerance": -1})"),
            "tracking_tolerance must be positive and finite [m], got -1");
}

// "auto" orientation weight: weighted where the arm can hold any orientation of the frame (its
// Jacobian of rank 6, also from a singular start), not on an arm that cannot (a planar arm: rank
// 3), which is said; a weight given is kept
TEST(TaskRun, AutoOrientationWeightFollowsWhatTheArmCanHold) {
  auto notice_of = [](const mj::TaskRun& run) {
    for (const std::string& n : run.notices()) {
      if (n.find("orientation not weighted") != std::string::npos) return n;
    }
    return std::string();
  };
  const mj::TaskRun planar(task_in_mjcf(R"({"model": "arm4.xml", "q0": [0.3, 0.2, 0.1, 0.1], "qref": 0,
      "duration": 0.01, "target": {"frame": "link3"}})"));
  EXPECT_EQ(planar.frame_target()->orientation_weight, 0.0);
  EXPECT_NE(notice_of(planar).find("has rank 3 < 6 with 4 joint(s)"), std::string::npos) << notice_of(planar);
  // the UR5e stretched out (every joint at 0) is singular there; 0.1 rad beside it it is not
  const mj::TaskRun stretched(task_in_mjcf(R"({"model": "ur5e.xml", "q0": [0, 0, 0, 0, 0, 0], "qref": 0,
      "duration": 0.01, "target": {"frame": "tip"}})"));
  EXPECT_EQ(stretched.frame_target()->orientation_weight, kAutoOrientationWeight);
  EXPECT_EQ(notice_of(stretched), "");
  const mj::TaskRun given(task_in_mjcf(R"({"model": "arm4.xml", "q0": [0.3, 0.2, 0.1, 0.1], "qref": 0,
      "duration": 0.01, "target": {"frame": "link3", "weights": {"orientation": 5}}})"));
  EXPECT_EQ(given.frame_target()->orientation_weight, 5.0);
  EXPECT_EQ(notice_of(given), "");
  EXPECT_EQ(error_of(R"({"model": "ur5e.xml", "target": {"frame": "tip", "weights": {"orientation": "some"}}})"),
            "task file 't.json', 'target', 'weights': field 'orientation': expected a number or \"auto\", got \"some\"");
}

// a planar arm's circle lies in the plane it moves in, with or without "facing" (arm4 moves in
// x–z; at q = 0 its tip is on the world's vertical axis), and runs counter-clockwise as the
// automatic camera sees that plane, from −y: from the start it heads for −x
TEST(TaskRun, APlanarArmsCircleLiesInItsPlaneAndRunsCounterClockwiseOnCamera) {
  for (const std::string& normal : {std::string(), std::string(R"(, "normal": "facing")")}) {
    const mj::TaskRun run(task_in_mjcf(R"({"model": "arm4.xml", "q0": [0, 0, 0, 0], "qref": 0, "duration": 0.01,
        "target": {"frame": "link3"}, "reference": {"shape": "circle", "radius": 0.1, "frequency": 0.5,
        "ramp": 0)" + normal + "}}"));
    ASSERT_TRUE(run.reference());
    VecX<double> p0(3), p(3), rate(3);
    run.reference()->sample(0.0, p0, rate);
    EXPECT_NEAR(p0[0], 0.0, 1e-12) << "the start is on the vertical axis";
    for (const double t : {0.1, 0.5, 1.0, 1.5}) {
      run.reference()->sample(t, p, rate);
      EXPECT_NEAR(p[1], p0[1], 1e-12) << "t = " << t << normal;
      EXPECT_NEAR((p - p0).norm(), 2 * 0.1 * std::sin(M_PI * 0.5 * t), 1e-9) << "t = " << t << normal;
    }
    run.reference()->sample(0.1, p, rate);
    EXPECT_LT(p[0], p0[0] - 1e-3) << normal;
  }
}

// a start as far out as the arm reaches (arm4 stretched, its Jacobian of lower rank there than
// beside it): the circle lies on the side the arm can reach, the start its point farthest from the
// base. Hanging down, the circle rises from the start (the default +z would put it out of reach
// below); stretched upright, the rule and the default agree
TEST(TaskRun, ACircleFromAStretchedStartLiesWithinReach) {
  for (const double q_first : {M_PI, 0.0}) {
    SCOPED_TRACE("q0[0] = " + std::to_string(q_first));
    const mj::TaskRun run(task_in_mjcf(R"({"model": "arm4.xml", "q0": [)" + std::to_string(q_first) +
                                       R"(, 0, 0, 0], "qref": 0, "duration": 0.01, "target": {"frame": "link3"},
        "reference": {"shape": "circle", "radius": 0.1, "frequency": 0.5, "ramp": 0}})"));
    const Vec3<double> base = run.controller().problem().model().link(0).X_tree.r;
    VecX<double> p0(3), p(3), rate(3);
    run.reference()->sample(0.0, p0, rate);
    const double reach = (p0 - base).norm();
    for (double t = 0.05; t < 2.0; t += 0.05) {
      run.reference()->sample(t, p, rate);
      EXPECT_LT((p - base).norm(), reach - 1e-6) << "t = " << t;
    }
    run.reference()->sample(1.0, p, rate);  // half a turn: the point opposite the start
    EXPECT_NEAR((p - p0).norm(), 0.2, 1e-9);
    EXPECT_NEAR(p[2] - p0[2], q_first == 0.0 ? -0.2 : 0.2, 1e-9);
  }
}

// an arm of two joints (a yaw and a pitch) moves its tip on a sphere about the pitch axis' pivot:
// its circle lies in the sphere's tangent plane at the start, the plane whose normal is the
// radius to the tip (within 1e-9 of it at every time)
TEST(TaskRun, ATwoJointArmsCircleLiesInTheTangentPlaneOfItsSurface) {
  const std::string model = ::testing::TempDir() + "yaw_pitch.xml";
  std::ofstream(model) << R"(<mujoco><worldbody>
    <body pos="0 0 0.2"><joint name="yaw" axis="0 0 1"/><inertial pos="0 0 0.05" mass="2" diaginertia="0.02 0.02 0.002"/>
      <body pos="0 0 0.16"><joint name="pitch" axis="0 1 0"/><inertial pos="0 0 0.15" mass="1.5" diaginertia="0.1 0.1 0.001"/>
        <site name="tip" pos="0 0 0.3"/></body></body></worldbody>
    <actuator><motor joint="yaw" ctrlrange="-20 20"/><motor joint="pitch" ctrlrange="-20 20"/></actuator></mujoco>)";
  Task task = task_from_json(nlohmann::json::parse(R"({"q0": [0.3, 0.7], "qref": "q0", "duration": 0.01,
      "target": {"frame": "tip"}, "reference": {"shape": "circle", "radius": 0.05, "frequency": 0.5, "ramp": 0}})"),
                             "two joints", arm_defaults());
  task.model = model;
  const mj::TaskRun run(task);
  ASSERT_TRUE(run.reference());
  VecX<double> p0(3), p(3), rate(3);
  run.reference()->sample(0.0, p0, rate);
  const Vec3<double> pivot(0, 0, 0.36);
  const Vec3<double> radial = (Vec3<double>(p0) - pivot).normalized();
  EXPECT_NEAR((Vec3<double>(p0) - pivot).norm(), 0.3, 1e-12) << "the tip";
  for (const double t : {0.2, 0.5, 1.0, 1.7}) {
    run.reference()->sample(t, p, rate);
    EXPECT_NEAR(radial.dot(Vec3<double>(p - p0)), 0.0, 1e-9) << "t = " << t;
    EXPECT_GT((p - p0).norm(), 1e-3) << "t = " << t;
  }
}

// Without a frame target a reference moves the joint target: from home to a pose in 1 s
// (minimum jerk), the arm following it and at rest on its end; the horizon's stages see the
// reference at their own times
TEST(TaskRun, AJointReferenceMovesTheJointTarget) {
  Task task = task_in_mjcf(R"({"model": "ur5e.xml", "q0": "home", "qref": "q0", "duration": 2, "solver": "cgmres",
      "reference": {"shape": "line", "to": [-1.3, -1.4, 1.4, -1.6, -1.571, 0.2], "duration": 1}})");
  mj::TaskRun run(task);  // (C/GMRES named: its residual is read below)
  ASSERT_TRUE(run.reference() && !run.frame_target());
  ASSERT_EQ(run.reference()->dim(), 6);
  VecX<double> end(6), rate(6);
  run.reference()->sample(10.0, end, rate);
  const mj::RunResult res = run.run();
  ASSERT_FALSE(res.diverged) << res.divergence_reason;
  // the final error is against the reference at the end, here its end value
  EXPECT_NEAR(res.final_q_error, (res.final_q - end).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT(res.final_q_error, 5e-3);
  EXPECT_TRUE(run.summary(res).reached);
  // at t = 0.5 the stages see the reference at 0.5 + i·Δτ, with its rate as the velocity target
  OcpProblem& problem = run.controller().nlp().problem();
  run.controller().nlp().set_time(0.5);
  VecX<double> U = VecX<double>::Zero(run.controller().nlp().dim()), F(U.size());
  run.controller().nlp().residual(U, res.final_q, VecX<double>::Zero(6), 0.5, F);
  const double dtau = 0.5 / problem.N();
  for (int i : {0, 7, problem.N()}) {
    VecX<double> q_ref(6), v_ref(6);
    run.reference()->sample(0.5 + i * dtau, q_ref, v_ref);
    EXPECT_LT((problem.terms().q_ref(i) - q_ref).cwiseAbs().maxCoeff(), 1e-15) << "stage " << i;
    EXPECT_LT((problem.terms().v_ref(i) - v_ref).cwiseAbs().maxCoeff(), 1e-15) << "stage " << i;
  }
  EXPECT_GT(problem.terms().v_ref(0).norm(), 0.5) << "mid-move, the reference moves";
}

}  // namespace
}  // namespace idmpc
