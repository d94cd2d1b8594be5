// The Controller owns the paper's timing (eqs. 27–28, DESIGN §6): which torque it returns from
// which solution, measured state and â_0, and the one-step lag with which the closed loop applies
// it. Each rule is recomputed here from the dynamics kernels, independently of the controller.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/closed_loop.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/solver/controller.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;

const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";

// the controller and this test evaluate the same RNEA on the same inputs: equal to the last bit
// but for the order in which Eigen may sum; any rule change moves τ by ≥ 1e-6 relative (below)
constexpr double kSameTorque = 1e-13;

double rel(const VecX<double>& a, const VecX<double>& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

struct Case {
  Formulation formulation;
  DerivativeMode mode;
};

class ControllerRule : public ::testing::TestWithParam<Case> {};

// τ(0) from the zero-horizon solution at the measured state, then 30 updates at the states of
// an Euler plant driven by the controller's torques from the swing-up start; once the arm moves,
// every term of the ID rule — q + Δt v, v + Δt â_0 with the previous a_0, the new a_0 — moves τ
TEST_P(ControllerRule, TorqueIsEqs27And28) {
  const Case c = GetParam();
  const test::Problem p = load_problem(kArm4);
  const Model& model = p.model;
  const int n = model.n;
  CgmresSettings cs;
  Controller controller(OcpProblem(model, c.formulation, c.mode, paper_weights(n), VecX<double>::Zero(n), 25), cs);
  const double dt = controller.dt();
  Data data(model);

  VecX<double> q = VecX<double>::Zero(n), v = VecX<double>::Zero(n);
  q[0] = -M_PI + 0.1;
  const VecX<double> tau0 = controller.initialize(q, v);
  VecX<double> a0_previous = controller.solver().solution().head(n);
  // at t = 0 the torque applies at once: no prediction
  const VecX<double> expected0 = c.formulation == Formulation::kForwardDynamics
                                     ? a0_previous
                                     : VecX<double>(rnea(model, data, q, v, a0_previous));
  EXPECT_LE(rel(tau0, expected0), kSameTorque);

  VecX<double> applied = tau0;
  for (int k = 0; k < 30; ++k) {
    SCOPED_TRACE("update " + std::to_string(k));
    const double t = k * dt;
    if (k > 0) {  // a semi-implicit Euler plant under the torque of the update before
      v += dt * aba(model, data, q, v, applied);
      q += dt * v;
      applied = controller.torque();
    }
    ASSERT_TRUE(controller.update(t, q, v)) << controller.failure();
    const VecX<double> U0 = controller.solver().solution().head(n);
    VecX<double> expected;
    if (c.formulation == Formulation::kForwardDynamics) {
      expected = U0;  // FD applies u_0 and ignores â_0
    } else {
      const VecX<double> q_pred = q + dt * v, v_pred = v + dt * a0_previous;
      expected = rnea(model, data, q_pred, v_pred, U0);
      // each ingredient matters at this state: the rule is pinned, not just plausible
      const VecX<double> no_prediction = rnea(model, data, q, v, U0);
      const VecX<double> new_a0 = rnea(model, data, q_pred, VecX<double>(v + dt * U0), U0);
      const VecX<double> no_velocity = rnea(model, data, q_pred, v, U0);
      if (k >= 20) {
        EXPECT_GT(rel(no_prediction, expected), 1e3 * kSameTorque);
        EXPECT_GT(rel(new_a0, expected), 1e3 * kSameTorque);
        EXPECT_GT(rel(no_velocity, expected), 1e3 * kSameTorque);
      }
      EXPECT_LE(rel(controller.applied_acceleration(), U0), 0.0);
    }
    EXPECT_LE(rel(controller.torque(), expected), kSameTorque);
    a0_previous = U0;
  }
}

INSTANTIATE_TEST_SUITE_P(Controllers, ControllerRule,
                         ::testing::Values(Case{Formulation::kForwardDynamics, DerivativeMode::kMatrix},
                                           Case{Formulation::kForwardDynamics, DerivativeMode::kAdjoint},
                                           Case{Formulation::kInverseDynamics, DerivativeMode::kMatrix},
                                           Case{Formulation::kInverseDynamics, DerivativeMode::kAdjoint}),
                         [](const auto& info) {
                           return to_string(info.param.formulation) + "_" + to_string(info.param.mode);
                         });

// In the closed loop the torque of the update at t_k is applied over [t_{k+1}, t_{k+2}): the row
// logged at t_k carries the torque of the previous update (the zero-horizon one at k = 0), and
// the plant's velocity change over that step is what that torque produces.
TEST(ClosedLoop, AppliesEachTorqueOneStepAfterItsUpdate) {
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    SCOPED_TRACE(to_string(f));
    const test::Problem p = load_problem(kArm4);
    const Model& model = p.model;
    const int n = model.n;
    CgmresSettings cs;
    Controller controller(OcpProblem(model, f, DerivativeMode::kAdjoint, paper_weights(n), VecX<double>::Zero(n), 25), cs);
    mj::Plant plant(p.m.get(), mj::import_model(p.m.get(), kArm4).actuation);
    mj::ClosedLoopSettings ls;
    ls.duration = 0.05;
    ls.q0 = VecX<double>::Zero(n);
    ls.q0[0] = -M_PI;
    ls.v0 = VecX<double>::Zero(n);
    ls.phase_timing = false;

    // what the controller returned before each row's update: its initialization, then updates
    Controller twin(OcpProblem(model, f, DerivativeMode::kAdjoint, paper_weights(n), VecX<double>::Zero(n), 25), cs);
    std::vector<VecX<double>> q, v, u, produced;
    produced.push_back(twin.initialize(ls.q0, ls.v0));
    const mj::RunResult r = mj::run_closed_loop(plant, controller, ls, [&](const mj::StepRecord& s) {
      q.push_back(s.q);
      v.push_back(s.v);
      u.push_back(s.u);
      produced.push_back(controller.torque());
    });
    ASSERT_FALSE(r.diverged) << r.divergence_reason;
    ASSERT_EQ(u.size(), 50u);
    for (size_t k = 0; k < u.size(); ++k) {
      SCOPED_TRACE("step " + std::to_string(k));
      EXPECT_EQ(u[k], produced[k]) << "row k must carry the torque produced one update earlier";
    }
    // the plant integrated exactly that torque: v_{k+1} = v_k + Δt FD(q_k, v_k, u_k), semi-implicit
    // Euler with no contact or limit on arm4 (MuJoCo's and our FD agree to 1e-10)
    Data data(model);
    for (size_t k = 0; k + 1 < u.size(); ++k) {
      const VecX<double> a = aba(model, data, q[k], v[k], u[k]);
      EXPECT_LE(rel(v[k + 1], VecX<double>(v[k] + controller.dt() * a)), 1e-9) << "step " << k;
    }
  }
}

}  // namespace
}  // namespace idmpc

namespace idmpc {
namespace {

// With actuator limits the controller clamps: every torque the plant receives is within them,
// the clamped steps are counted per joint, and the record keeps both the applied and the
// commanded torque (the plant integrates the applied one).
TEST(ClosedLoop, ClampsCountsAndRecordsSaturatedTorques) {
  const test::Problem p = load_problem(kArm4);
  const Model& model = p.model;
  const int n = model.n;
  constexpr double kLimit = 20.0;  // N m: the swing-up commands ~200 at first
  Controller controller(OcpProblem(model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, paper_weights(n),
                                   VecX<double>::Zero(n), 25),
                        CgmresSettings{});
  controller.set_torque_limits(VecX<double>::Constant(n, -kLimit), VecX<double>::Constant(n, kLimit));
  mj::Plant plant(p.m.get(), mj::import_model(p.m.get(), kArm4).actuation);
  mj::ClosedLoopSettings ls;
  ls.duration = 0.1;
  ls.q0 = VecX<double>::Zero(n);
  ls.q0[0] = -M_PI;
  ls.v0 = VecX<double>::Zero(n);
  ls.phase_timing = false;
  std::vector<VecX<double>> q, v, u, uc;
  const mj::RunResult r = mj::run_closed_loop(plant, controller, ls, [&](const mj::StepRecord& s) {
    q.push_back(s.q);
    v.push_back(s.v);
    u.push_back(s.u);
    uc.push_back(s.u_commanded);
  });
  std::vector<long> clamped(static_cast<size_t>(n), 0);
  long any = 0;
  for (size_t k = 0; k + 1 < u.size() || (!r.diverged && k < u.size()); ++k) {
    EXPECT_LE(u[k].cwiseAbs().maxCoeff(), kLimit) << "step " << k;
    bool row = false;
    for (int j = 0; j < n; ++j) {
      if (u[k][j] != uc[k][j]) {
        EXPECT_EQ(std::abs(u[k][j]), kLimit);
        EXPECT_GT(std::abs(uc[k][j]), kLimit);
        ++clamped[static_cast<size_t>(j)];
        row = true;
      } else {
        EXPECT_LE(std::abs(uc[k][j]), kLimit);
      }
    }
    any += row;
  }
  EXPECT_GT(any, 10) << "the limit must bind in this test";
  EXPECT_EQ(r.saturated_steps, clamped);
  EXPECT_EQ(r.saturated_any, any);
  // the plant integrated the applied (clamped) torque
  Data data(model);
  for (size_t k = 0; k + 1 < u.size(); ++k) {
    const VecX<double> a = aba(model, data, q[k], v[k], u[k]);
    EXPECT_LE(rel(v[k + 1], VecX<double>(v[k] + controller.dt() * a)), 1e-9) << "step " << k;
  }
}

}  // namespace
}  // namespace idmpc
