// A C/GMRES update allocates no heap memory once the controller exists: every variant (FD/ID ×
// matrix/adjoint × single/multiple shooting, with and without torque limits) is a hot path.
// Allocations are counted by support/count_allocations.hpp.
#include <gtest/gtest.h>

#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <tuple>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/controller.hpp"
#include "idmpc/solver/riccati.hpp"
#include "idmpc/solver/shooting.hpp"
#include "support/problems.hpp"
#include "support/count_allocations.hpp"


namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;
using test::Problem;

using test::CountAllocations;

TEST(NoMallocCounter, IsArmed) {
  EXPECT_GE(test::allocations_of_a_vector(), 1)
      << "the counter must see an Eigen allocation, or the test below proves nothing";
}

using Variant = std::tuple<Formulation, DerivativeMode, ShootingScheme, bool, Products>;

// a solver of the variant on arm4, started (initialized and updated once: the first update may
// size workspaces) at a state away from the target
class NoMallocUpdate : public ::testing::TestWithParam<Variant> {
 protected:
  void SetUp() override {
    const auto& [formulation, mode, shooting, limited, products] = GetParam();
    const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
    const double inf = std::numeric_limits<double>::infinity();
    const TorqueLimits limits = limited ? TorqueLimits{(VecX<double>(4) << -20, -inf, -20, -inf).finished(),
                                                       (VecX<double>(4) << 20, inf, 20, inf).finished()}
                                        : TorqueLimits{};
    ocp_ = std::make_unique<Shooting>(p.model, formulation, mode, paper_weights(4), VecX<double>::Zero(4), 25, limits);
    s_.shooting = shooting;
    s_.products = products;
    solver_ = std::make_unique<Cgmres>(*ocp_, s_);
    solver_->initialize(0.5, q_, v_);
    ASSERT_TRUE(solver_->update(0.5, q_, v_));
  }
  // allocations during `before` and three updates
  template <typename Before> long allocations_of_updates(Before before) {
    CountAllocations c;
    before();
    for (int k = 1; k <= 3; ++k) {
      if (!solver_->update(0.5 + k * s_.dt, q_, v_)) ADD_FAILURE() << "update " << k << ": " << solver_->failure();
    }
    return c.count();
  }
  const VecX<double> q_ = (VecX<double>(4) << -1.5, 0.25, 0.27, -0.23).finished();
  const VecX<double> v_ = (VecX<double>(4) << 2.0, -1.0, 0.5, 0.3).finished();
  CgmresSettings s_;
  std::unique_ptr<Shooting> ocp_;
  std::unique_ptr<Cgmres> solver_;
};

TEST_P(NoMallocUpdate, UpdatesAfterTheFirstDoNotAllocate) {
  EXPECT_EQ(allocations_of_updates([] {}), 0);
}

// a target set between updates (OcpProblem::set_target: the cost's q_ref and the torque reference
// ID(q_ref, 0, 0) − d̂ recomputed in place) allocates nothing, nor do the updates after it
TEST_P(NoMallocUpdate, SetTargetThenUpdateDoesNotAllocate) {
  const VecX<double> target = (VecX<double>(4) << 0.1, -0.2, 0.15, 0.05).finished();
  EXPECT_EQ(allocations_of_updates([&] { ocp_->problem().set_target(target); }), 0);
  EXPECT_EQ(ocp_->problem().cost().q_ref(), target);
}

// a frame target with a moving position and a moving joint target: the stages' references are
// sampled in place at each new time (and the ID torque references recomputed), the frame's
// kinematics and Jᵀf run in preallocated workspaces
TEST_P(NoMallocUpdate, WithAFrameTargetAndMovingReferencesUpdatesDoNotAllocate) {
  FrameTarget target;
  target.frame = Frame{"link3 tip", 3, Transform<double>{}};
  target.frame.placement.r = Vec3<double>(0, 0, 0.5);
  target.position_weight.setConstant(10);  // a target out of reach: heavier weights drive FD to divergence
  target.orientation_weight = 1;
  ocp_->problem().set_frame_target(target);
  ocp_->problem().set_frame_trajectory(std::make_shared<const CircleTrajectory>(
      Vec3<double>(0.5, 0, 5), Vec3<double>::UnitY(), 0.1, 0.5, Vec3<double>::UnitZ(), 0.2));
  MatX<double> waypoints(4, 2);
  waypoints << q_, VecX<double>::Zero(4);
  ocp_->problem().set_joint_trajectory(
      std::make_shared<const WaypointTrajectory>(std::vector<double>{0.5, 1.5}, waypoints));
  ASSERT_TRUE(solver_->update(0.5, q_, v_)) << solver_->failure();
  EXPECT_EQ(allocations_of_updates([] {}), 0);
}

// the controller's own work per update (eqs. 27–28, the disturbance observer handing d̂ to the
// horizon) allocates nothing either, with the friction in the model
TEST(NoMallocController, UpdatesWithTheObserverDoNotAllocate) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const Model model = with_joint_friction(p.model, VecX<double>::Constant(4, 0.5), VecX<double>::Constant(4, 0.1));
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    SCOPED_TRACE(to_string(f));
    CgmresSettings s;
    s.alpha = 0;  // a full horizon from the start, near the upright target
    s.init_full_horizon = true;
    Controller controller(OcpProblem(model, f, DerivativeMode::kAdjoint, paper_weights(4), VecX<double>::Zero(4), 25), s,
                          std::make_shared<const Model>(model));
    controller.set_disturbance_observer(0.02);
    // a plant: the same model with a constant torque the controller does not know, explicit Euler
    Data plant(model);
    const VecX<double> unknown = (VecX<double>(4) << 0.3, -0.2, 0.1, 0.05).finished();
    VecX<double> q = (VecX<double>(4) << -0.1, 0.05, 0.07, -0.03).finished();
    VecX<double> v = (VecX<double>(4) << 0.2, -0.1, 0.05, 0.03).finished();
    VecX<double> tau = controller.initialize(q, v), force(4);
    long allocations = 0;
    for (int k = 0; k < 6; ++k) {
      {
        CountAllocations c;
        ASSERT_TRUE(controller.update(k * s.dt, q, v)) << controller.failure();
        if (k >= 2) allocations += c.count();  // the first updates may size workspaces
      }
      force = tau + unknown;
      v += s.dt * aba(model, plant, q, v, force);
      q += s.dt * v;
      tau = controller.torque();
    }
    EXPECT_EQ(allocations, 0);
    EXPECT_TRUE((controller.disturbance().array() != 0).any()) << "the observer must have run";
  }
}

// the Riccati solver's update (local models, recursion, step) allocates nothing either, in both
// formulations, with torque limits, a frame target and a moving joint target
TEST(NoMallocRiccati, UpdatesDoNotAllocate) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const double inf = std::numeric_limits<double>::infinity();
  const TorqueLimits limits{(VecX<double>(4) << -20, -inf, -20, -inf).finished(),
                            (VecX<double>(4) << 20, inf, 20, inf).finished()};
  const VecX<double> q = (VecX<double>(4) << -1.5, 0.25, 0.27, -0.23).finished();
  const VecX<double> v = (VecX<double>(4) << 2.0, -1.0, 0.5, 0.3).finished();
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    SCOPED_TRACE(to_string(f));
    OcpProblem problem(p.model, f, DerivativeMode::kMatrix, paper_weights(4), VecX<double>::Zero(4), 25, limits);
    FrameTarget target;
    target.frame = Frame{"link3 tip", 3, Transform<double>{}};
    target.frame.placement.r = Vec3<double>(0, 0, 0.5);
    target.position_weight.setConstant(10);
    target.orientation_weight = 1;
    problem.set_frame_target(target);
    MatX<double> waypoints(4, 2);
    waypoints << q, VecX<double>::Zero(4);
    problem.set_joint_trajectory(std::make_shared<const WaypointTrajectory>(std::vector<double>{0.5, 1.5}, waypoints));
    RiccatiSettings rs;
    rs.iterations = 2;
    rs.line_search = true;  // the merit's evaluations too
    RiccatiSolver solver(problem, 0.5, 1e-3, rs);
    solver.initialize(0.5, q, v);
    ASSERT_TRUE(solver.update(0.501, q, v)) << solver.failure();
    CountAllocations c;
    for (int k = 2; k <= 4; ++k) {
      if (!solver.update(0.5 + k * 1e-3, q, v)) ADD_FAILURE() << solver.failure();
    }
    EXPECT_EQ(c.count(), 0);
  }
}

// under-actuated: FD's n_u inputs, ID's elimination of the passive torques, the terminal P
TEST(NoMallocRiccati, UnderActuatedUpdatesDoNotAllocate) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/cartpole.xml");
  const double inf = std::numeric_limits<double>::infinity();
  const TorqueLimits limits{(VecX<double>(2) << -10, -inf).finished(), (VecX<double>(2) << 10, inf).finished()};
  const VecX<double> q = (VecX<double>(2) << 0.2, 0.3).finished(), v = (VecX<double>(2) << 0.5, -1.0).finished();
  MatX<double> P = MatX<double>::Identity(4, 4);
  P(0, 1) = P(1, 0) = 0.3;
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    SCOPED_TRACE(to_string(f));
    OcpProblem problem(p.model, f, DerivativeMode::kMatrix, paper_weights(2), VecX<double>::Zero(2), 25, limits);
    problem.set_terminal_weight(P);
    RiccatiSettings rs;
    rs.iterations = 2;
    rs.line_search = true;
    RiccatiSolver solver(problem, 0.5, 1e-3, rs);
    solver.initialize(0.0, q, v);
    ASSERT_TRUE(solver.update(0.001, q, v)) << solver.failure();
    CountAllocations c;
    for (int k = 2; k <= 4; ++k) {
      if (!solver.update(k * 1e-3, q, v)) ADD_FAILURE() << solver.failure();
    }
    EXPECT_EQ(c.count(), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Controllers, NoMallocUpdate,
    ::testing::Combine(::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics),
                       ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint),
                       ::testing::Values(ShootingScheme::kSingle, ShootingScheme::kMultiple), ::testing::Bool(),
                       ::testing::Values(Products::kDifference, Products::kExact)),
    [](const auto& info) {
      const Variant& v = info.param;
      return to_string(std::get<0>(v)) + "_" + to_string(std::get<1>(v)) + "_" + to_string(std::get<2>(v)) +
             (std::get<3>(v) ? "_limits" : "") + (std::get<4>(v) == Products::kExact ? "_exact" : "");
    });

}  // namespace
}  // namespace idmpc
