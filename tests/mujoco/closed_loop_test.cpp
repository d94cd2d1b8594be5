// run_closed_loop's own bookkeeping: the closed-loop cost is the task's stage cost at each
// step's own time, and a MuJoCo error in the plant ends the run as a recorded divergence instead
// of escaping. Short runs of the paper's arm (60 control steps at most).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "idmpc/dynamics/rnea.hpp"
#include "idmpc/experiment/task.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc {
namespace {

constexpr double kDuration = 0.06;  // s: 60 control steps

struct Row {
  double t;
  VecX<double> q, v, u;
};

// arm4 reaching along a moving joint reference (a minimum-jerk line over 0.1 s, 0.3 rad per
// joint), no observer (d̂ = 0), with or without a fixed compute latency
Task moving_reach(const std::string& formulation, const std::string& latency) {
  Task task = task_from_json(
      {{"model", IDMPC_SOURCE_DIR "/mjcf/arm4.xml"}, {"q0", {-0.5, 0.3, 0, 0}}, {"qref", "q0"},
       {"reference", {{"shape", "line"}, {"to", {-0.2, 0.6, 0.3, 0.3}}, {"duration", 0.1}}},
       {"offset_free", false}, {"torque_limit", 60}, {"solver", "cgmres"},
       {"cgmres", {{"alpha", 1}, {"init_full_horizon", false}}}},
      "moving reach", arm_defaults());
  task.formulation = formulation;
  task.duration = kDuration;
  task.latency = latency;
  return task;
}

// Σ Δt·L(q_k, v_k, u_k) with the references of t_k, recomputed from the run's rows: the joint
// reference sampled at t_k, its rate the velocity reference, u_ref = ID(q_ref, 0, 0) (no d̂)
TEST(ClosedLoopCost, IsTheStageCostAtEachStepsOwnTime) {
  for (const std::string formulation : {"fd", "id"}) {
    for (const std::string latency : {"none", "2.6"}) {  // 2.6 ms: an update every third step
      SCOPED_TRACE(formulation + ", latency " + latency);
      mj::TaskRun run(moving_reach(formulation, latency));
      mj::ClosedLoopSettings ls = run.loop_settings();
      ls.phase_timing = false;
      std::vector<Row> rows;
      const mj::RunResult result =
          run.run(ls, [&](const mj::StepRecord& s) { rows.push_back({s.t, s.q, s.v, s.u}); });
      ASSERT_FALSE(result.diverged) << result.divergence_reason;
      ASSERT_EQ(static_cast<long>(rows.size()), 60);

      const OcpProblem& problem = run.controller().problem();
      ASSERT_EQ(problem.disturbance(), VecX<double>::Zero(4));
      const Trajectory& reference = *problem.terms().joint_trajectory();
      const Model& model = problem.model();
      const OcpWeights& w = problem.weights();
      Data data(model);
      const VecX<double> zero = VecX<double>::Zero(4);
      VecX<double> q_ref(4), v_ref(4);
      auto quadratic = [](const VecX<double>& e, const VecX<double>& W) { return 0.5 * e.dot(W.cwiseProduct(e)); };
      double expected = 0, stale = 0;
      const double dt = run.controller().dt();
      for (const Row& r : rows) {
        reference.sample(r.t, q_ref, v_ref);
        const VecX<double> u_ref = rnea(model, data, q_ref, zero, zero);
        expected += dt * (quadratic(r.q - q_ref, w.Qq) + quadratic(r.v - v_ref, w.Qv) + quadratic(r.u - u_ref, w.R));
        // the same a period later: how far a reference time off by one period moves the sum
        reference.sample(r.t + dt, q_ref, v_ref);
        const VecX<double> u_late = rnea(model, data, q_ref, zero, zero);
        stale += dt * (quadratic(r.q - q_ref, w.Qq) + quadratic(r.v - v_ref, w.Qv) + quadratic(r.u - u_late, w.R));
      }
      EXPECT_NEAR(result.closed_loop_cost, expected, 1e-10 * expected);
      ASSERT_GT(std::abs(stale - expected), 1e-4 * expected) << "the reference must move in this test";
    }
  }
}

// A MuJoCo error inside mj_step (here raised by a control callback from the 10th step on): the run
// ends there as a divergence whose reason is MuJoCo's message, with the state measured last
TEST(ClosedLoopMujocoError, EndsTheRunAndIsReportedNotThrown) {
  mj::TaskRun run(moving_reach("id", "none"));
  struct Callback {  // restores MuJoCo's global callback whatever happens
    Callback() {
      mjcb_control = [](const mjModel*, mjData* d) {
        if (d->time > 0.0095) mju_error("deliberate error of the test's control callback");
      };
    }
    ~Callback() { mjcb_control = nullptr; }
  } callback;
  std::vector<double> times;
  mj::RunResult result;
  ASSERT_NO_THROW(result = run.run([&](const mj::StepRecord& s) { times.push_back(s.t); }));
  EXPECT_TRUE(result.diverged);
  EXPECT_NE(result.divergence_reason.find("MuJoCo error: deliberate error of the test's control callback"),
            std::string::npos)
      << result.divergence_reason;
  EXPECT_NEAR(result.diverged_at, 0.010, 1e-9);
  EXPECT_EQ(result.steps, 11);
  ASSERT_FALSE(times.empty());
  EXPECT_NEAR(times.back(), 0.010, 1e-9);
  EXPECT_EQ(result.final_q.size(), 4);
  EXPECT_TRUE(result.final_q.allFinite());
}

}  // namespace
}  // namespace idmpc
