// C/GMRES (formulations.md §C/GMRES) on the four controllers (FD/ID × matrix/adjoint): the zero-horizon
// initialization solves F = 0, the matrix-free Fréchet products are directional derivatives of
// F, an update solves the continuation equation and makes F decay as Ḟ = −ζF, and bad
// settings are refused with a message naming them.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <Eigen/SVD>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>

#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/solver/shooting.hpp"
#include "support/problems.hpp"
#include "idmpc/solver/cgmres.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;
using test::Problem;
using test::random_vector;

const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
const std::string kTree = IDMPC_SOURCE_DIR "/mjcf/tree.xml";

// zero-horizon Newton stops at ‖F_0‖ ≤ 1e-10 (init_tolerance); every stage of the T = 0
// problem sees the same x, so the full residual is √N times that at worst (measured ≤ 4e-12:
// F_0 is affine in U, Newton converges in one step)
constexpr double kInitResidual = 1e-9;
// forward difference with h = 1e-8 against a central one with 1e-5 (and the central-difference
// Jacobian): the forward side carries truncation h‖F''‖‖W‖²/2 and rounding ε‖F‖/h, the central
// ones 1e-10. Measured ≤ 1e-6 on arm4, up to 3e-5 for FD on tree.xml (light bodies under
// random torques: huge accelerations, ‖F''‖ and ‖F‖ large against ‖(∂F/∂U)W‖)
constexpr double kFrechetMatch = 1e-4;
// with kmax = dim GMRES solves exactly the system whose products are h = 1e-8 forward
// differences; those carry rounding ε‖F‖/h ≈ 1e-7·‖∂F/∂U‖ (matrix mode adds more, measured
// 1e-6 for FD), so U̇ has that backward error. The forward error is cond(∂F/∂U) times larger:
// cond ≈ 2.5e5 for FD, 1.7e3 for ID at the test state, hence a backward-error check
constexpr double kContinuationSolved = 1e-5;
// one update on the controller's own Euler model obeys F₁ = (1 − ζΔt)F₀ + O(Δt²): halving Δt
// divides the miss by 4 (measured 4.00–4.23 over Δt = 1 ms … 0.125 ms); the O(Δt·1e-7) GMRES
// and forward-difference errors are far below the smallest O(Δt²) term
constexpr double kSecondOrderRatio = 0.5;
// ID's O(Δt²) term is small at the paper's Δt = 1 ms, ζ = 100 (measured 1.6e-2·ζΔt), FD's
// is not (measured 10·ζΔt: its U̇ is large as ∂F/∂u ≈ R + O(Δτ M⁻²) is ill-conditioned)
constexpr double kIdFirstOrderFraction = 0.1;
// geometric decay (1 − ζΔt)^k = 0.9^300 ≈ 2e-14 stalls at the floor set by the O(Δt²) terms
// and the kmax = 10 GMRES error; measured 1.5e-5 (FD) and 2.6e-7 (ID) after 300 updates
constexpr double kDecayedResidual = 1e-3;

std::string name(const std::string& path) { return path.substr(path.find_last_of('/') + 1); }

using Controller = std::tuple<Formulation, DerivativeMode>;
std::string controller_name(const Controller& c) {
  return to_string(std::get<0>(c)) + "_" + to_string(std::get<1>(c));
}
const auto kControllers =
    ::testing::Combine(::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics),
                       ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint));

// ---------------------------------------------------------------------------------------------
// (a) zero-horizon initialization

class ZeroHorizon
    : public ::testing::TestWithParam<std::tuple<std::string, Formulation, DerivativeMode>> {};

TEST_P(ZeroHorizon, InitializationSolvesTheFullProblemAtTZero) {
  const auto& [path, formulation, mode] = GetParam();
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 10;
  for (double Qa : {0.0, 1e-4}) {
    if (formulation == Formulation::kForwardDynamics && Qa > 0) continue;  // no Q_a in FD
    for (unsigned seed = 1; seed <= 5; ++seed) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", Qa " + std::to_string(Qa));
      std::mt19937 rng(seed);
      const VecX<double> q0 = random_vector(rng, n, 2.0), v0 = random_vector(rng, n, 1.0);
      Shooting ocp(p.model, formulation, mode, paper_weights(n, Qa), VecX<double>::Zero(n), N);
      Cgmres solver(ocp, CgmresSettings{});
      const double reached = solver.initialize(0.0, q0, v0);
      EXPECT_LE(reached, kInitResidual);
      EXPECT_DOUBLE_EQ(solver.horizon(0.0), 0.0);
      // T = 0: the one-stage solution copied to every stage solves the N-stage problem
      VecX<double> F(ocp.dim());
      ocp.residual(solver.solution(), q0, v0, 0.0, F);
      EXPECT_LE(F.norm(), kInitResidual);
      for (int i = 1; i < N; ++i) {
        EXPECT_EQ(solver.solution().segment(i * n, n), solver.solution().head(n)) << "stage " << i;
      }
      EXPECT_TRUE(solver.solution_rate().isZero(0.0));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, ZeroHorizon,
    ::testing::Combine(::testing::Values(kArm4, kTree),
                       ::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics),
                       ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint)),
    [](const auto& info) {
      const std::string file = name(std::get<0>(info.param));
      return file.substr(0, file.size() - 4) + "_" + to_string(std::get<1>(info.param)) + "_" +
             to_string(std::get<2>(info.param));
    });

// ---------------------------------------------------------------------------------------------
// (b) the matrix-free products are directional derivatives of F

class Frechet : public ::testing::TestWithParam<std::tuple<std::string, Formulation, DerivativeMode>> {};

TEST_P(Frechet, ForwardDifferenceProductMatchesCentralDifferenceAndJacobian) {
  const auto& [path, formulation, mode] = GetParam();
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 4, dim = N * n;
  const double T = 0.3;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    Shooting ocp(p.model, formulation, mode, paper_weights(n, 1e-4), VecX<double>::Zero(n), N);
    const VecX<double> q0 = random_vector(rng, n, 2.0), v0 = random_vector(rng, n, 1.0);
    const VecX<double> U = random_vector(rng, dim, 5.0), W = random_vector(rng, dim, 1.0);
    auto F = [&](const VecX<double>& X) {
      VecX<double> out(dim);
      ocp.residual(X, q0, v0, T, out);
      return out;
    };
    // what C/GMRES computes, h = 1e-8
    const double h = CgmresSettings{}.h;
    const VecX<double> forward = (F(U + h * W) - F(U)) / h;
    // a central difference with a much larger step
    const double hc = 1e-5;
    const VecX<double> central = (F(U + hc * W) - F(U - hc * W)) / (2 * hc);
    EXPECT_LE((forward - central).norm() / central.norm(), kFrechetMatch);
    // J·W with J built column by column by the library's central-difference helper
    const MatX<double> J = central_difference_jacobian(F, U);
    const VecX<double> JW = J * W;
    EXPECT_LE((forward - JW).norm() / JW.norm(), kFrechetMatch);
    EXPECT_LE((central - JW).norm() / JW.norm(), kFrechetMatch);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, Frechet,
    ::testing::Combine(::testing::Values(kArm4, kTree),
                       ::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics),
                       ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint)),
    [](const auto& info) {
      const std::string file = name(std::get<0>(info.param));
      return file.substr(0, file.size() - 4) + "_" + to_string(std::get<1>(info.param)) + "_" +
             to_string(std::get<2>(info.param));
    });

// ---------------------------------------------------------------------------------------------
// (c) the continuation: an update solves (∂F/∂U) U̇ = −ζF − (∂F/∂x)ẋ − ∂F/∂t, and F decays

class Continuation : public ::testing::TestWithParam<Controller> {};

// a mid-swing state of arm4 (the first link half-way, moving)
void mid_swing(VecX<double>& q, VecX<double>& v) {
  q = (VecX<double>(4) << -1.5, 0.25, 0.27, -0.23).finished();
  v = (VecX<double>(4) << 2.0, -1.0, 0.5, 0.3).finished();
}

TEST_P(Continuation, UpdateWithFullKrylovSpaceSolvesTheContinuationEquation) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  const int n = 4, N = 4, dim = N * n;
  Shooting ocp(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N);
  Shooting probe(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N);
  CgmresSettings s;
  s.kmax = dim;
  Cgmres solver(ocp, s);
  VecX<double> q, v;
  mid_swing(q, v);
  const double t = 0.5;
  solver.initialize(t, q, v);
  const VecX<double> U = solver.solution();

  // the continuation system as formulations.md §C/GMRES writes it, evaluated independently
  const double h = s.h, zeta = 1.0 / s.dt, T = solver.horizon(t), Th = solver.horizon(t + h);
  VecX<double> F(dim), Fx(dim);
  probe.residual(U, q, v, T, F);
  const VecX<double> a0 = probe.first_acceleration();
  const VecX<double> qh = q + h * v, vh = v + h * a0;
  probe.residual(U, qh, vh, Th, Fx);
  const VecX<double> b = -zeta * F - (Fx - F) / h;
  const MatX<double> J = central_difference_jacobian(
      [&](const VecX<double>& X) {
        VecX<double> out(dim);
        probe.residual(X, qh, vh, Th, out);
        return out;
      },
      U);

  ASSERT_TRUE(solver.update(t, q, v));
  EXPECT_DOUBLE_EQ(solver.residual_norm(), F.norm());
  const VecX<double>& Udot = solver.solution_rate();
  // backward error: U̇ solves a system within kContinuationSolved·‖J‖ of the true one
  const double normJ = Eigen::JacobiSVD<MatX<double>>(J).singularValues()(0);
  EXPECT_LE((J * Udot - b).norm() / (normJ * Udot.norm()), kContinuationSolved)
      << "GMRES iterations " << solver.gmres_iterations();
  EXPECT_LE(((solver.solution() - U) / s.dt - Udot).norm(), 1e-9 * Udot.norm());
}

TEST_P(Continuation, UpdateCostsKmaxPlusThreeEvaluations) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  Shooting ocp(p.model, formulation, mode, paper_weights(4), VecX<double>::Zero(4), 25);
  CgmresSettings s;
  s.kmax = 5;
  Cgmres solver(ocp, s);
  VecX<double> q, v;
  mid_swing(q, v);
  solver.initialize(0.5, q, v);
  ASSERT_TRUE(solver.update(0.5, q, v));
  EXPECT_EQ(solver.gmres_iterations(), s.kmax);
  // F, F at the predicted state, GMRES's initial residual, then one per iteration
  EXPECT_EQ(solver.evaluations(), s.kmax + 3);
}

// the controller's own model as the plant: x ← x + Δt (v, a_0), t ← t + Δt, which is exactly the
// motion the update assumes, so F(U, x, t) obeys Ḟ = −ζF up to O(Δt²) and the GMRES error
struct EulerPlant {
  VecX<double> q, v;
  double t;
};

// F at the plant's state, and the plant's acceleration a_0 under the current solution
double residual_at(Shooting& probe, const Cgmres& solver, const EulerPlant& x, VecX<double>* a0,
                   VecX<double>* F_out = nullptr) {
  VecX<double> F(probe.dim());
  probe.residual(solver.solution(), x.q, x.v, solver.horizon(x.t), F);
  if (a0) *a0 = probe.first_acceleration();
  if (F_out) *F_out = F;
  return F.norm();
}

TEST_P(Continuation, OneUpdateReducesTheResidualByOneMinusZetaDt) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  const int n = 4, N = 4;
  const double zeta = 100;
  double previous_error = 0;
  for (double dt : {1e-3, 5e-4, 2.5e-4, 1.25e-4}) {
    SCOPED_TRACE("dt " + std::to_string(dt));
    Shooting ocp(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N);
    Shooting probe(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N);
    CgmresSettings s;
    s.kmax = N * n;  // exact linear solve: only the O(Δt²) terms remain
    s.zeta = zeta;
    s.dt = dt;
    Cgmres solver(ocp, s);
    EulerPlant x{{}, {}, 0.5};  // growing horizon: ∂F/∂t ≠ 0 is part of the prediction
    mid_swing(x.q, x.v);
    solver.initialize(x.t, x.q, x.v);
    VecX<double> a0, F0, F1;
    residual_at(probe, solver, x, &a0, &F0);
    ASSERT_TRUE(solver.update(x.t, x.q, x.v));
    x.q += s.dt * x.v;
    x.v += s.dt * a0;
    x.t += s.dt;
    residual_at(probe, solver, x, nullptr, &F1);
    // the update decreases ‖F‖, and misses the first-order prediction by O(Δt²)
    const double error = (F1 - (1 - zeta * dt) * F0).norm() / F0.norm();
    EXPECT_LT(F1.norm(), F0.norm());
    if (previous_error > 0) {
      EXPECT_NEAR(previous_error / error, 4.0, kSecondOrderRatio) << "errors " << previous_error << ", " << error;
    }
    if (formulation == Formulation::kInverseDynamics && dt == 1e-3) {
      EXPECT_LE(error, kIdFirstOrderFraction * zeta * dt);
    }
    previous_error = error;
  }
}

TEST_P(Continuation, RepeatedUpdatesDriveTheResidualDownGeometrically) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  const int n = 4, N = 25;
  Shooting ocp(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N);
  Shooting probe(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N);
  CgmresSettings s;  // kmax = 10, Δt = 1 ms
  s.alpha = 0;       // fixed horizon T_f: ∂F/∂t = 0
  s.zeta = 0.1 / s.dt;
  Cgmres solver(ocp, s);
  // near the upright target, at rest: the one-stage initial guess is far from the N-stage
  // optimum (‖F_0‖ = O(1)–O(100)) but the dynamics stay tame while C/GMRES closes the gap
  EulerPlant x{(VecX<double>(4) << -0.15, 0.025, 0.027, -0.023).finished(), VecX<double>::Zero(4), 0.0};
  solver.initialize(x.t, x.q, x.v);
  VecX<double> a0;
  const double F0 = residual_at(probe, solver, x, &a0);
  ASSERT_GT(F0, 1e-3);
  double F = F0;
  for (int k = 1; k <= 300; ++k) {
    ASSERT_TRUE(solver.update(x.t, x.q, x.v)) << "update " << k;
    x.q += s.dt * x.v;
    x.v += s.dt * a0;
    x.t += s.dt;
    F = residual_at(probe, solver, x, &a0);
    if (k == 50) {
      // the first 50 updates follow (1 − ζΔt)^k = 0.9^50 ≈ 5.2e-3 closely (measured 5.2e-3 for
      // ID, 3.8e-3 for FD) before the floor is reached
      EXPECT_LE(F, 2 * std::pow(1 - s.zeta * s.dt, 50) * F0);
    }
  }
  EXPECT_LE(F, kDecayedResidual * F0) << "F0 " << F0 << ", F300 " << F;
}

INSTANTIATE_TEST_SUITE_P(Controllers, Continuation, kControllers,
                         [](const auto& info) { return controller_name(info.param); });

// At a frozen state the update still assumes ẋ = (v, a_0), so its fixed point is
// ζF = −(∂F/∂x)ẋ, not F = 0: "updates at a frozen x drive F to 0" is not a property of
// C/GMRES. For ID at rest it converges to that fixed point, which we check.
TEST(FrozenState, ConvergesToTheContinuationFixedPointNotToZero) {
  const Problem p = load_problem(kArm4);
  const int n = 4, N = 10;
  for (DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
    SCOPED_TRACE(to_string(mode));
    Shooting ocp(p.model, Formulation::kInverseDynamics, mode, paper_weights(n), VecX<double>::Zero(n), N);
    Shooting probe(p.model, Formulation::kInverseDynamics, mode, paper_weights(n), VecX<double>::Zero(n), N);
    CgmresSettings s;
    s.alpha = 0;
    s.zeta = 0.1 / s.dt;
    Cgmres solver(ocp, s);
    VecX<double> q, v = VecX<double>::Zero(n);
    mid_swing(q, v);
    v.setZero();
    solver.initialize(0.0, q, v);
    for (int k = 0; k < 400; ++k) ASSERT_TRUE(solver.update(0.0, q, v));
    // U̇ → 0, and the residual balances the assumed motion of the state
    VecX<double> F(ocp.dim()), Fx(ocp.dim());
    probe.residual(solver.solution(), q, v, s.Tf, F);
    const VecX<double> a0 = probe.first_acceleration();
    probe.residual(solver.solution(), q + s.h * v, v + s.h * a0, s.Tf, Fx);
    const VecX<double> balance = s.zeta * F + (Fx - F) / s.h;
    EXPECT_LE(balance.norm(), 1e-3 * s.zeta * F.norm());
    EXPECT_LE(solver.solution_rate().norm() * s.dt, 1e-3 * solver.solution().norm());
  }
}

// ---------------------------------------------------------------------------------------------
// (c') torque limits: the stage block (input, d, ρ) in the initializations and the update

// ±bound on joints 0 and 2 of arm4, joints 1 and 3 unbounded
TorqueLimits arm4_limits(double bound) {
  const double inf = std::numeric_limits<double>::infinity();
  return TorqueLimits{(VecX<double>(4) << -bound, -inf, -bound, -inf).finished(),
                      (VecX<double>(4) << bound, inf, bound, inf).finished()};
}

// every stage's torque within its bounds, d > 0 and ρ > 0
void expect_inside(const Shooting& ocp, const VecX<double>& U, const TorqueLimits& limits, double slack) {
  const int n = ocp.n(), m = ocp.problem().m(), sd = ocp.stage_dim();
  for (int i = 0; i < ocp.N(); ++i) {
    SCOPED_TRACE("stage " + std::to_string(i));
    for (int j : ocp.problem().torque_bounds().joints()) {
      EXPECT_LE(ocp.torques()(j, i), limits.upper[j] + slack) << "joint " << j;
      EXPECT_GE(ocp.torques()(j, i), limits.lower[j] - slack) << "joint " << j;
    }
    EXPECT_GT(U.segment(i * sd + n, m).minCoeff(), 0.0) << "d";
    EXPECT_GT(U.segment(i * sd + n + m, m).minCoeff(), 0.0) << "ρ";
  }
}

// The zero-horizon Newton with limits the unconstrained one-stage torque violates (random
// velocities: u ≈ u_ref − R⁻¹M⁻¹Q_v v, hundreds of N m against a 20 N m bound): F = 0 on the whole
// stage block, with the torque pushed inside (by the dummy weight's barrier, d ≈ r_d/(2sρ)
// keeps it a little inside the bound) and d, ρ > 0.
TEST_P(Continuation, ZeroHorizonInitializationWithTorqueLimits) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  const int n = 4, N = 10;
  const TorqueLimits limits = arm4_limits(20.0);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    const VecX<double> q0 = random_vector(rng, n, 2.0), v0 = random_vector(rng, n, 1.0);
    Shooting ocp(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N, limits);
    Cgmres solver(ocp, CgmresSettings{});
    EXPECT_LE(solver.initialize(0.0, q0, v0), kInitResidual);
    VecX<double> F(ocp.dim());
    ocp.residual(solver.solution(), q0, v0, 0.0, F);
    EXPECT_LE(F.norm(), kInitResidual);
    expect_inside(ocp, solver.solution(), limits, 0.0);
  }
}

// With init_full_horizon and an open horizon (α = 0), the initialization solves the N-stage
// problem itself: from rest far from the target the optimal torques press against the bounds
// over the first stages. Without limits the same start solves the unconstrained problem, in
// both cases to init_tolerance·√dim: the continuation's levels may stop at 1e-8 of their start
// ‖F‖, the problem itself is then polished (measured ≤ 5e-10; 1.2e-8 for FD adjoint without
// the polish, where the last level stopped at 1e-8 of its start).

TEST_P(Continuation, FullHorizonInitializationWithAndWithoutTorqueLimits) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  const int n = 4, N = 25;
  const VecX<double> q0 = (VecX<double>(4) << -2.0, 0.3, -0.2, 0.1).finished(), v0 = VecX<double>::Zero(n);
  CgmresSettings s;
  s.alpha = 0;
  s.init_full_horizon = true;
  for (const bool limited : {false, true}) {
    SCOPED_TRACE(limited ? "limits" : "no limits");
    const TorqueLimits limits = limited ? arm4_limits(20.0) : TorqueLimits{};
    Shooting ocp(p.model, formulation, mode, paper_weights(n), VecX<double>::Zero(n), N, limits);
    Cgmres solver(ocp, s);
    const double tolerance = s.init_tolerance * std::sqrt(static_cast<double>(ocp.dim()));
    EXPECT_LE(solver.initialize(0.0, q0, v0), tolerance);
    VecX<double> F(ocp.dim());
    ocp.residual(solver.solution(), q0, v0, s.Tf, F);
    EXPECT_LE(F.norm(), tolerance);
    if (limited) {
      expect_inside(ocp, solver.solution(), limits, 0.0);
      // the bound is reached: the first stage's torque on joint 0 within 1 % of it
      EXPECT_GE(ocp.torques().col(0).cwiseAbs()[0], 0.99 * 20.0);
    } else {
      EXPECT_GT(ocp.torques().col(0).cwiseAbs()[0], 20.0);  // the limits above do bind
    }
  }
}

// The full-horizon start solves the problem by the Riccati solver first, then polishes by
// Newton–GMRES. On a heavy planar two-link arm (drawn by tools/arm_population.py) the
// continuation alone stalls in FD at ‖F‖ = 148 (measured), whence the closed loop diverged at
// 35 ms; from the Riccati solver's solution both formulations reach the tolerance.
const char* kHeavyTwoLink = R"(<mujoco model="heavy_two_link">
  <worldbody>
    <body name="link0" pos="0 0 0.2"><joint name="joint0" axis="0 1 0"/>
      <inertial pos="0 0 0.183661" mass="12.3146" diaginertia="0.139694 0.139694 0.00123146"/>
      <body name="link1" pos="0 0 0.367321"><joint name="joint1" axis="0 1 0"/>
        <inertial pos="0 0 0.0946371" mass="9.30557" diaginertia="0.0287113 0.0287113 0.000930557"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="joint0" ctrllimited="true" ctrlrange="-175.032 175.032"/>
    <motor joint="joint1" ctrllimited="true" ctrlrange="-32.2527 32.2527"/></actuator>
</mujoco>)";

TEST_P(Continuation, FullHorizonStartFromTheRiccatiSolution) {
  const auto& [formulation, mode] = GetParam();
  mj::ModelPtr m = mj::load_model_from_string(kHeavyTwoLink);
  const Model model = mj::import_model(m.get(), "heavy_two_link.xml").model;
  const VecX<double> q0 = (VecX<double>(2) << 0.39166573353688694, -0.4673388790854809).finished();
  const VecX<double> q_ref = (VecX<double>(2) << -0.3221416709640257, -1.3983380994135193).finished();
  const OcpWeights w{VecX<double>::Constant(2, 100.0), VecX<double>::Constant(2, 10.0), VecX<double>::Zero(2),
                     (VecX<double>(2) << 0.000938, 0.467).finished()};
  TorqueLimits limits;
  limits.lower = (VecX<double>(2) << -175.032, -32.2527).finished();
  limits.upper = -limits.lower;
  Shooting ocp(model, formulation, mode, w, q_ref, 25, limits);
  CgmresSettings s;
  s.alpha = 0;
  s.init_full_horizon = true;
  Cgmres solver(ocp, s);
  const double tolerance = s.init_tolerance * std::sqrt(static_cast<double>(ocp.dim()));
  EXPECT_LE(solver.initialize(0.0, q0, VecX<double>::Zero(2)), tolerance);
  expect_inside(ocp, solver.solution(), limits, 0.0);
}

// With limits an update first makes (d, ρ) consistent with the torques at the measured state
// (one more evaluation of F), then runs as without.
TEST_P(Continuation, UpdateWithTorqueLimitsCostsKmaxPlusFourEvaluations) {
  const auto& [formulation, mode] = GetParam();
  const Problem p = load_problem(kArm4);
  Shooting ocp(p.model, formulation, mode, paper_weights(4), VecX<double>::Zero(4), 25, arm4_limits(20.0));
  CgmresSettings s;
  s.kmax = 5;
  Cgmres solver(ocp, s);
  VecX<double> q, v;
  mid_swing(q, v);
  solver.initialize(0.5, q, v);
  ASSERT_TRUE(solver.update(0.5, q, v));
  EXPECT_EQ(solver.gmres_iterations(), s.kmax);
  EXPECT_EQ(solver.evaluations(), s.kmax + 4);
}

// ---------------------------------------------------------------------------------------------
// (d) bad settings are refused, naming the setting

template <typename Fn> void expect_invalid(Fn&& fn, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "no exception; expected one naming '" << needle << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message '" << e.what() << "' does not name '" << needle << "'";
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type, message: " << e.what();
  }
}

class BadSettings : public ::testing::Test {
 protected:
  BadSettings() : p_(load_problem(kArm4)) {}
  Shooting make_ocp(int N = 5) {
    return Shooting(p_.model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, paper_weights(4),
               VecX<double>::Zero(4), N);
  }
  void expect_refused(const CgmresSettings& s, const std::string& needle) {
    SCOPED_TRACE(needle);
    expect_invalid([&] { s.validate(); }, needle);
    expect_invalid([&] {
      Shooting ocp = make_ocp();
      Cgmres solver(ocp, s);
    }, needle);
  }
  Problem p_;
};

TEST_F(BadSettings, DefaultsAreValid) {
  EXPECT_NO_THROW(CgmresSettings{}.validate());
  Shooting ocp = make_ocp();
  EXPECT_NO_THROW(Cgmres(ocp, CgmresSettings{}));
}

TEST_F(BadSettings, KmaxBelowOne) {
  CgmresSettings s;
  s.kmax = 0;
  expect_refused(s, "kmax");
}

TEST_F(BadSettings, NonPositiveDt) {
  for (double dt : {0.0, -1e-3, std::nan("")}) {
    CgmresSettings s;
    s.dt = dt;
    expect_refused(s, "dt");
  }
}

TEST_F(BadSettings, NonPositiveTf) {
  for (double Tf : {0.0, -0.5}) {
    CgmresSettings s;
    s.Tf = Tf;
    expect_refused(s, "Tf");
  }
}

TEST_F(BadSettings, NonPositiveH) {
  for (double h : {0.0, -1e-8}) {
    CgmresSettings s;
    s.h = h;
    expect_refused(s, "increment h");
  }
}

TEST_F(BadSettings, NegativeZetaAndAlpha) {
  CgmresSettings s;
  s.zeta = -1;
  expect_refused(s, "zeta");
  s = CgmresSettings{};
  s.alpha = -1;
  expect_refused(s, "alpha");
}

// the full-horizon start needs a horizon of length Tf at t = 0: with α > 0 it would do nothing
TEST_F(BadSettings, FullHorizonStartWithAGrowingHorizon) {
  CgmresSettings s;
  s.init_full_horizon = true;
  s.alpha = 1.0;
  expect_refused(s, "init_full_horizon needs alpha = 0");
  s.alpha = 0;
  EXPECT_NO_THROW(s.validate());
}

TEST_F(BadSettings, HorizonStepsBelowOne) {
  expect_invalid([&] { make_ocp(0); }, "N");
  expect_invalid([&] { make_ocp(-3); }, "N");
}

TEST_F(BadSettings, WeightsOfTheWrongSize) {
  for (const char* which : {"Qq", "Qv", "Qa", "R"}) {
    SCOPED_TRACE(which);
    OcpWeights w = paper_weights(4);
    VecX<double>& bad = std::string(which) == "Qq"   ? w.Qq
                        : std::string(which) == "Qv" ? w.Qv
                        : std::string(which) == "Qa" ? w.Qa
                                                     : w.R;
    bad = VecX<double>::Ones(3);
    expect_invalid([&] {
      Shooting(p_.model, Formulation::kForwardDynamics, DerivativeMode::kMatrix, w, VecX<double>::Zero(4), 5);
    }, which);
  }
  expect_invalid([&] {
    Shooting(p_.model, Formulation::kInverseDynamics, DerivativeMode::kMatrix, paper_weights(4),
        VecX<double>::Zero(5), 5);
  }, "q_ref");
}

TEST_F(BadSettings, ForwardDynamicsNeedsPositiveR) {
  OcpWeights w = paper_weights(4);
  w.R[2] = 0;
  expect_invalid([&] {
    Shooting(p_.model, Formulation::kForwardDynamics, DerivativeMode::kAdjoint, w, VecX<double>::Zero(4), 5);
  }, "R");
}

TEST(ParseNames, UnknownFormulationAndDerivativeMode) {
  EXPECT_EQ(parse_formulation("fd"), Formulation::kForwardDynamics);
  EXPECT_EQ(parse_formulation("id"), Formulation::kInverseDynamics);
  EXPECT_EQ(parse_derivative_mode("matrix"), DerivativeMode::kMatrix);
  EXPECT_EQ(parse_derivative_mode("adjoint"), DerivativeMode::kAdjoint);
  for (const std::string bad : {"FD", "xyz", ""}) {
    expect_invalid([&] { parse_formulation(bad); }, "'" + bad + "'");
  }
  expect_invalid([&] { parse_formulation("inverse"); }, "formulation");
  expect_invalid([&] { parse_derivative_mode("exact"); }, "'exact'");
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    EXPECT_EQ(parse_formulation(to_string(f)), f);
  }
  for (DerivativeMode d : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
    EXPECT_EQ(parse_derivative_mode(to_string(d)), d);
  }
}

}  // namespace
}  // namespace idmpc
