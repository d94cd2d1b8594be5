// Compute latency in the closed loop (formulations.md §Compute latency): with latency on, the torque computed from the
// state measured at t reaches the plant ⌈t_compute/δt⌉ plant steps later and is held until the
// next one arrives; the controller starts no update while it is busy; an update slower than the
// control period is a deadline miss. With a fixed latency every figure is deterministic, so these
// tests run the paper's arm (δt = Δt = 1 ms) with fixed latencies and check the loop step by step
// against a controller replayed on the measured states.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "idmpc/experiment/task.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc {
namespace {

constexpr double kDuration = 0.06;  // s: 60 control steps

struct Row {
  double t;
  VecX<double> q, v, u;
  double update_ms;
};

// the paper's swing-up, its first steps
Task swingup(const std::string& formulation, const std::string& latency) {
  Task task = paper_task();
  task.model = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
  task.formulation = formulation;
  task.derivatives = "adjoint";
  task.duration = kDuration;
  task.latency = latency;
  return task;
}

// the paper's arm under the defaults for real arms (offset-free tracking on) with torque limits
// that bind, from half a radian below the upright target, its horizon growing (alpha = 1) from a
// zero-horizon start: FD survives a latency of a few periods here (not on the paper's swing-up)
Task reach(const std::string& formulation, const std::string& latency) {
  Task task = task_from_json(
      {{"model", IDMPC_SOURCE_DIR "/mjcf/arm4.xml"}, {"q0", {-0.5, 0.3, 0, 0}}, {"qref", {0, 0, 0, 0}},
       {"torque_limit", 60}, {"solver", "cgmres"}, {"cgmres", {{"alpha", 1}, {"init_full_horizon", false}}}},
      "reach", arm_defaults());
  task.formulation = formulation;
  task.duration = kDuration;
  task.latency = latency;
  return task;
}

struct LoopRun {
  mj::RunResult result;
  std::vector<Row> rows;
};

LoopRun run(const Task& task) {
  mj::TaskRun run(task);
  mj::ClosedLoopSettings ls = run.loop_settings();
  ls.phase_timing = false;
  LoopRun out;
  out.result = run.run(ls, [&](const mj::StepRecord& s) { out.rows.push_back({s.t, s.q, s.v, s.u, s.update_ms}); });
  EXPECT_FALSE(out.result.diverged) << out.result.divergence_reason;
  return out;
}

class FixedLatency : public ::testing::TestWithParam<std::string> {};

// a latency of k plant steps: the plant's torque at step j is the one the controller computed
// from the state measured k steps earlier (at the last update by then), held in between; the
// initialization's torque until the first one arrives
TEST_P(FixedLatency, DelaysTheTorqueByWholePlantSteps) {
  const std::string formulation = GetParam();
  for (const int k : {1, 3}) {
    SCOPED_TRACE("latency of " + std::to_string(k) + " plant steps, " + formulation);
    // 0.4 ms short of k steps: rounded up to k
    const LoopRun r = run(reach(formulation, std::to_string(k - 0.4)));
    ASSERT_EQ(static_cast<long>(r.rows.size()), std::lround(kDuration / 1e-3));

    // the same controller replayed on the measured states of the update steps, each torque
    // aimed k steps ahead, its observer told the torque held over the k steps before
    mj::TaskRun replay(reach(formulation, "none"));
    Controller& c = replay.controller();
    std::vector<VecX<double>> expected(r.rows.size(), c.initialize(r.rows[0].q, r.rows[0].v));
    size_t updates = 0;
    for (size_t j = 0; j < r.rows.size(); ++j) {
      // the controller is busy for k steps after each update
      const bool update_step = j % static_cast<size_t>(k) == 0;
      ASSERT_EQ(std::isfinite(r.rows[j].update_ms), update_step) << "step " << j;
      if (!update_step) continue;
      ++updates;
      const bool ok = j == 0 ? c.update(r.rows[j].t, r.rows[j].q, r.rows[j].v)
                             : c.update(r.rows[j].t, r.rows[j].q, r.rows[j].v, k * 1e-3, expected[j - 1]);
      ASSERT_TRUE(ok) << c.failure();
      ASSERT_TRUE(c.aim(k * 1e-3));
      for (size_t i = j + static_cast<size_t>(k); i < r.rows.size(); ++i) expected[i] = c.torque();
    }
    for (size_t j = 0; j < r.rows.size(); ++j) {
      ASSERT_EQ(r.rows[j].u, expected[j]) << "plant step " << j;
    }
    EXPECT_EQ(r.result.updates, static_cast<long>(updates));
    EXPECT_EQ(r.result.deadline_misses, k > 1 ? r.result.updates : 0);
  }
}

// the paper's timing is a latency of one period: none and any fixed latency up to Δt (one plant
// step here; 0 included: a torque never acts at its own measurement's instant) run the same loop
// to the last bit, the observer included
TEST_P(FixedLatency, NoneIsALatencyOfOnePeriod) {
  const LoopRun none = run(reach(GetParam(), "none"));
  for (const char* latency : {"0", "0.25", "1"}) {
    const LoopRun late = run(reach(GetParam(), latency));
    ASSERT_EQ(late.rows.size(), none.rows.size());
    for (size_t j = 0; j < none.rows.size(); ++j) {
      ASSERT_EQ(late.rows[j].q, none.rows[j].q) << latency << " ms, step " << j;
      ASSERT_EQ(late.rows[j].v, none.rows[j].v) << latency << " ms, step " << j;
      ASSERT_EQ(late.rows[j].u, none.rows[j].u) << latency << " ms, step " << j;
    }
    EXPECT_EQ(late.result.deadline_misses, 0);
    EXPECT_EQ(late.result.final_q, none.result.final_q);
  }
}

// a compute time longer than the run: no update's torque arrives, the plant holds the
// initialization's torque throughout, and the controller stays busy after its first update; the
// same for compute times beyond the range of the plant-step counter (1e19 ms and more)
TEST_P(FixedLatency, BeyondTheRunNoTorqueArrives) {
  for (const char* latency : {"100", "1e19", "1e300"}) {
    SCOPED_TRACE(std::string(latency) + " ms, " + GetParam());
    const LoopRun r = run(reach(GetParam(), latency));
    ASSERT_EQ(static_cast<long>(r.rows.size()), std::lround(kDuration / 1e-3));
    for (const Row& row : r.rows) ASSERT_EQ(row.u, r.rows.front().u) << "t = " << row.t;
    EXPECT_EQ(r.result.updates, 1);
    EXPECT_EQ(r.result.deadline_misses, 1);
  }
}

INSTANTIATE_TEST_SUITE_P(Formulations, FixedLatency, ::testing::Values("fd", "id"));

// none runs the paper's loop (formulations.md §The torque rule) unchanged: update at t, the previous torque applied over
// [t, t + Δt), the new one from t + Δt
TEST(Latency, NoneRunsThePapersLoop) {
  const Task task = swingup("id", "none");
  const LoopRun r = run(task);
  mj::TaskRun reference(task);
  mj::Plant& plant = reference.plant();
  Controller& c = reference.controller();
  plant.reset(reference.q0(), VecX<double>::Zero(reference.n()));
  VecX<double> tau = c.initialize(plant.q(), plant.v());
  for (size_t k = 0; k < r.rows.size(); ++k) {
    ASSERT_EQ(r.rows[k].q, plant.q()) << "step " << k;
    ASSERT_EQ(r.rows[k].u, tau) << "step " << k;
    ASSERT_TRUE(c.update(static_cast<double>(k) * c.dt(), plant.q(), plant.v()));
    std::string reason;
    ASSERT_TRUE(plant.step(tau, &reason)) << reason;
    tau = c.torque();
  }
}

TEST(Latency, EveryUpdateSlowerThanThePeriodIsADeadlineMiss) {
  // 2.5 ms at Δt = 1 ms: busy for 3 control steps, each update a miss
  const LoopRun slow = run(reach("fd", "2.5"));
  ASSERT_EQ(slow.rows.size(), 60u);
  EXPECT_EQ(slow.result.updates, 20);
  EXPECT_EQ(slow.result.deadline_misses, 20);
  // exactly one period is no miss
  EXPECT_EQ(run(reach("fd", "1")).result.deadline_misses, 0);
}

TEST(Latency, TheSummaryRecordsTheSettingAndTheMisses) {
  const Task task = reach("id", "2.5");
  mj::TaskRun r(task);
  mj::ClosedLoopSettings ls = r.loop_settings();
  ls.phase_timing = false;
  const nlohmann::json j = to_json(r.summary(r.run(ls)));
  EXPECT_EQ(j.at("latency"), (nlohmann::json{{"setting", "2.5"}, {"control_period_ms", 1.0}, {"updates", 20},
                                              {"deadline_misses", 20}}));
  EXPECT_EQ(j.at("task").at("latency"), 2.5);
  EXPECT_GT(j.at("joint_error_rms").get<double>(), 0);
  const RunSummary back = summary_from_json(j, "summary");
  EXPECT_EQ(back.task.latency, "2.5");
  EXPECT_EQ(back.deadline_misses, 20);
  EXPECT_EQ(back.updates, 20);
}

TEST(Latency, TheDelayedTorqueStaysWithinTheActuatorsRange) {
  for (const char* f : {"fd", "id"}) {
    const LoopRun r = run(reach(f, "2.6"));
    long saturated = 0;
    for (const Row& row : r.rows) {
      EXPECT_LE(row.u.cwiseAbs().maxCoeff(), 60.0) << f << ", t = " << row.t;
      saturated += row.u.cwiseAbs().maxCoeff() == 60.0;
    }
    EXPECT_GT(saturated, 0) << f << ": the limit must bind for the test to mean anything";
    EXPECT_EQ(r.result.saturated_any, saturated) << f;
  }
}

// a torque arriving within a control period takes over at its plant step
TEST(Latency, ThePlantSwitchesTorqueWithinAPeriod) {
  mj::ModelPtr m = mj::load_model(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  m->opt.timestep = 5e-4;
  mj::Plant two(m.get(), mj::Actuation{}), one(m.get(), mj::Actuation{});
  ASSERT_EQ(two.set_control_period(1e-3), "");
  ASSERT_EQ(two.substeps(), 2);
  ASSERT_EQ(one.set_control_period(5e-4), "");
  const VecX<double> q0 = (VecX<double>(4) << -3.0, 0.2, -0.1, 0.3).finished(), v0 = VecX<double>::Zero(4);
  const VecX<double> a = VecX<double>::Constant(4, 5.0), b = VecX<double>::Constant(4, -7.0);
  for (int switch_at = 0; switch_at <= 2; ++switch_at) {
    two.reset(q0, v0);
    one.reset(q0, v0);
    std::string reason;
    ASSERT_TRUE(two.step(a, switch_at, b, &reason)) << reason;
    ASSERT_TRUE(one.step(switch_at > 0 ? a : b, &reason)) << reason;
    ASSERT_TRUE(one.step(switch_at > 1 ? a : b, &reason)) << reason;
    EXPECT_EQ(VecX<double>(two.q()), VecX<double>(one.q())) << "switch after " << switch_at;
    EXPECT_EQ(VecX<double>(two.v()), VecX<double>(one.v())) << "switch after " << switch_at;
  }
  EXPECT_THROW(two.step(a, 3, b, nullptr), std::invalid_argument);
}

TEST(Latency, ParsesNoneMeasuredAndMilliseconds) {
  EXPECT_EQ(parse_latency("none").kind, Latency::Kind::kNone);
  EXPECT_EQ(parse_latency("measured").kind, Latency::Kind::kMeasured);
  EXPECT_EQ(parse_latency("2.5").ms, 2.5);
  EXPECT_EQ(parse_latency("0").kind, Latency::Kind::kFixed);
  EXPECT_EQ(to_string(parse_latency("1e-1")), "0.1");
  for (const char* bad : {"", "-1", "fast", "inf", "nan", "1e999", "010", "0x1", " 1", "1ms", "+1", "NONE"}) {
    try {
      parse_latency(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("got '") + bad + "'"), std::string::npos) << e.what();
    }
  }
}

TEST(Latency, TaskFieldErrorsNameTheFileAndField) {
  const nlohmann::json good = {{"latency", 2}};
  EXPECT_EQ(task_from_json(good, "task file 'x.json'", arm_defaults()).latency, "2");
  EXPECT_EQ(task_from_json({{"latency", "measured"}}, "task file 'x.json'", arm_defaults()).latency, "measured");
  for (const nlohmann::json& bad : {nlohmann::json(-1), nlohmann::json("fast"), nlohmann::json(""),
                                    nlohmann::json(true), nlohmann::json(1e308 * 10)}) {
    try {
      task_from_json({{"latency", bad}}, "task file 'x.json'", arm_defaults());
      ADD_FAILURE() << "accepted " << bad.dump();
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("task file 'x.json': field 'latency': expected", 0), 0u) << e.what();
    }
  }
  // a task without latency writes none (its JSON, and so the sweep's keys, as before)
  EXPECT_FALSE(to_json(arm_defaults()).contains("latency"));
  Task t = arm_defaults();
  t.latency = "measured";
  EXPECT_EQ(to_json(t).at("latency"), "measured");
  t.latency = "0.5";
  EXPECT_EQ(to_json(t).at("latency"), 0.5);
  t.latency = "slow";
  EXPECT_THROW(resolve(t, 4), std::invalid_argument);
}

}  // namespace
}  // namespace idmpc
