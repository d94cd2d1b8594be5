// The Riccati solver (solver/riccati.hpp) against what it must solve: converged, its inputs make
// C/GMRES's optimality residual F vanish (F is computed by the shooting sweep, an independent
// derivation: Pontryagin's costates instead of the stage local models), in both formulations,
// with a frame target and a moving reference; with torque limits the solution stays within
// them and lies on them where the unconstrained one would leave them.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <string>

#include "idmpc/mujoco/import.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "idmpc/solver/controller.hpp"
#include "idmpc/solver/riccati.hpp"
#include "idmpc/solver/shooting.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;
using test::random_vector;

constexpr double kTf = 0.5;
constexpr int kN = 20;

RiccatiSettings converged() {
  RiccatiSettings s;
  s.init_iterations = 200;
  s.init_tolerance = 1e-10;
  return s;
}

// ‖F‖ of C/GMRES's single-shooting residual at the Riccati solution's inputs (no limits)
double cgmres_residual(const OcpProblem& problem, const RiccatiSolver& solver, double t) {
  Shooting shooting(problem);
  shooting.set_time(t);
  const int n = problem.n();
  const VecX<double> U = Eigen::Map<const VecX<double>>(solver.inputs().data(), n * problem.N());
  VecX<double> F(U.size());
  shooting.residual(U, solver.states().col(0).head(n), solver.states().col(0).tail(n), kTf, F);
  return F.norm();
}

class RiccatiSolution : public ::testing::TestWithParam<Formulation> {};

TEST_P(RiccatiSolution, ConvergedInputsZeroTheShootingResidual) {
  const Formulation f = GetParam();
  for (const char* file : {"arm4.xml", "panda.xml"}) {
    const test::Problem p = load_problem(std::string(IDMPC_SOURCE_DIR "/mjcf/") + file);
    const int n = p.model.n;
    std::mt19937 rng(3);
    OcpWeights w{VecX<double>::Constant(n, 10.0), VecX<double>::Constant(n, 1.0),
                 VecX<double>::Constant(n, f == Formulation::kInverseDynamics ? 1e-4 : 0.0),
                 VecX<double>::Constant(n, 1e-3)};
    OcpProblem problem(p.model, f, DerivativeMode::kMatrix, w, random_vector(rng, n, 0.5), kN);
    RiccatiSolver solver(problem, kTf, 1e-3, converged());
    const VecX<double> q = random_vector(rng, n, 0.5), v = random_vector(rng, n, 0.5);
    const double kkt = solver.initialize(0.0, q, v);
    EXPECT_LT(kkt, 1e-8) << file;
    // at a converged multiple-shooting point the defects vanish: the states are the rollout
    EXPECT_LT(cgmres_residual(solver.problem(), solver, 0.0), 1e-6) << file;
    // one more converged update from a nearby state: still a solution of that state's problem
    RiccatiSettings more = converged();
    more.iterations = 50;
    more.tolerance = 1e-10;
    more.line_search = true;
    RiccatiSolver again(problem, kTf, 1e-3, more);
    again.initialize(0.0, q, v);
    ASSERT_TRUE(again.update(1e-3, q + 1e-3 * v, v));
    EXPECT_LT(cgmres_residual(again.problem(), again, 1e-3), 1e-6) << file;
  }
}

TEST_P(RiccatiSolution, WithAFrameTargetAndAMovingReference) {
  const Formulation f = GetParam();
  const test::Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/panda.xml");
  const int n = p.model.n;
  std::mt19937 rng(5);
  OcpWeights w{VecX<double>::Constant(n, 1.0), VecX<double>::Constant(n, 1.0), VecX<double>::Zero(n),
               VecX<double>::Constant(n, 1e-3)};
  const VecX<double> q0 = random_vector(rng, n, 0.5);
  OcpProblem problem(p.model, f, DerivativeMode::kMatrix, w, q0, kN);
  FrameTarget target;
  target.frame = Frame{"flange", n - 1, Transform<double>{}};
  target.position_weight = Vec3<double>::Constant(1e3);
  target.orientation_weight = 10;
  FrameKinematics<double> fk(p.model, target.frame);
  fk.compute(p.model, q0);
  target.position = fk.position();
  target.rotation = fk.rotation();
  problem.set_frame_target(target);
  problem.set_frame_trajectory(std::make_shared<CircleTrajectory>(fk.position(), Vec3<double>(0, 0, 1), 0.05, 0.5,
                                                                   Vec3<double>(1, 0, 0), 0.0));
  RiccatiSolver solver(problem, kTf, 1e-3, converged());
  const double kkt = solver.initialize(0.2, q0, VecX<double>::Zero(n));
  EXPECT_LT(kkt, 1e-8);
  EXPECT_LT(cgmres_residual(solver.problem(), solver, 0.2), 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Formulations, RiccatiSolution,
                         ::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics),
                         [](const auto& info) { return to_string(info.param); });

// The paper's arm held horizontal needs more torque than the limits allow: the solution keeps
// every stage torque within them, and the first stages' shoulder torque lies on its bound (the
// barrier's gap μ/z is a small fraction of the range)
TEST_P(RiccatiSolution, TorqueLimitsHoldAndBind) {
  const Formulation f = GetParam();
  const test::Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const int n = p.model.n;
  OcpWeights w = paper_weights(n, f == Formulation::kInverseDynamics ? 1e-4 : 0.0);
  const double limit = 20;
  TorqueLimits limits{VecX<double>::Constant(n, -limit), VecX<double>::Constant(n, limit)};
  VecX<double> q_ref = VecX<double>::Zero(n);
  q_ref[0] = 1.2;  // leaning over: the shoulder's holding torque exceeds the limit
  OcpProblem problem(p.model, f, DerivativeMode::kMatrix, w, q_ref, kN, limits);
  RiccatiSolver solver(problem, kTf, 1e-3, converged());
  solver.initialize(0.0, q_ref, VecX<double>::Zero(n));
  const MatX<double>& T = solver.torques();
  EXPECT_LE(T.cwiseAbs().maxCoeff(), limit * (1 + 1e-9));
  EXPECT_LE(solver.constraint_violation(), 0.0);
  // the unconstrained holding torque leaves the range, so the shoulder pushes at its bound
  EXPECT_GT(std::abs(problem.terms().u_ref(0)[0]), limit);
  EXPECT_GT(std::abs(T(0, 0)), 0.99 * limit);
}

// The barrier is recentred at the torque reference: a target held within limits that are far
// from symmetric about its holding torque is a solution, at rest on the target with the holding
// torque (an uncentred barrier would pull it off by its slope there)
TEST_P(RiccatiSolution, LimitsMoveNoTargetHeldWithinThem) {
  const Formulation f = GetParam();
  const test::Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const int n = p.model.n;
  VecX<double> q_ref = VecX<double>::Zero(n);
  q_ref[0] = 0.6;
  OcpProblem probe(p.model, f, DerivativeMode::kMatrix, paper_weights(n), q_ref, kN);
  const VecX<double> hold = probe.terms().u_ref(0);
  // each torque range reaches 5 N m past the holding torque on one side, 60 N m on the other
  TorqueLimits limits{hold - VecX<double>::Constant(n, 5.0), hold + VecX<double>::Constant(n, 60.0)};
  OcpProblem problem(p.model, f, DerivativeMode::kMatrix, paper_weights(n), q_ref, kN, limits);
  RiccatiSolver solver(problem, kTf, 1e-3, converged());
  solver.initialize(0.0, q_ref, VecX<double>::Zero(n));
  for (int i = 0; i <= kN; ++i) {
    EXPECT_LT((solver.states().col(i).head(n) - q_ref).cwiseAbs().maxCoeff(), 1e-9) << "stage " << i;
  }
  for (int i = 0; i < kN; ++i) {
    EXPECT_LT((solver.torques().col(i) - hold).cwiseAbs().maxCoeff(), 1e-7) << "stage " << i;
  }
}

TEST(RiccatiSettingsCheck, BadSettingsAreRefusedByName) {
  RiccatiSettings s;
  s.iterations = 0;
  EXPECT_THROW(s.validate(), std::invalid_argument);
  s = {};
  s.barrier = 0;
  EXPECT_THROW(s.validate(), std::invalid_argument);
  s = {};
  s.tolerance = -1;
  EXPECT_THROW(s.validate(), std::invalid_argument);
  try {
    RiccatiSettings bad;
    bad.init_iterations = -3;
    bad.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("init_iterations"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_solver("newton"), std::invalid_argument);
  EXPECT_EQ(parse_solver("riccati"), SolverKind::kRiccati);
}

// The controller drives either solver through one interface; its torque rule reads the first
// stage's input of the Riccati solution as it does C/GMRES's
TEST(RiccatiController, SwingsThePaperArmUpAndSettles) {
  const test::Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const int n = p.model.n;
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    ControllerSettings s;
    s.formulation = f;
    s.derivatives = DerivativeMode::kMatrix;
    s.solver = SolverKind::kRiccati;
    s.N = 25;
    s.weights = paper_weights(n);
    s.q_ref = VecX<double>::Zero(n);
    Controller c(std::make_shared<const Model>(p.model), s);
    EXPECT_EQ(c.solver_kind(), SolverKind::kRiccati);
    EXPECT_THROW(c.nlp(), std::logic_error);
    // an Euler plant of the controller's own model, one step per period
    VecX<double> q = VecX<double>::Zero(n), v = VecX<double>::Zero(n);
    q[0] = -M_PI;
    VecX<double> tau = c.initialize(q, v);
    ASSERT_TRUE(c.failure().empty()) << c.failure();
    Data data(p.model);
    const double dt = c.dt();
    for (int k = 1; k <= 8000; ++k) {
      const VecX<double> a = aba(p.model, data, q, v, tau);
      q += dt * v;
      v += dt * a;
      const VecX<double> next = c.torque();
      ASSERT_TRUE(c.update(k * dt, q, v)) << to_string(f) << " at step " << k << ": " << c.failure();
      tau = next;
    }
    EXPECT_LT(q.cwiseAbs().maxCoeff(), 1e-4) << to_string(f) << ": " << q.transpose();
    // a Controller moves with its solver
    Controller moved = std::move(c);
    EXPECT_EQ(moved.solver_kind(), SolverKind::kRiccati);
    EXPECT_TRUE(moved.update(8001 * dt, q, v));
  }
}

}  // namespace
}  // namespace idmpc
