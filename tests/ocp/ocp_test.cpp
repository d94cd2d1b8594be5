// The two formulations and two derivative modes: same residual across modes, the residual is
// the gradient of the discretized cost, and the two formulations agree where they must.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/reference.hpp"
#include "idmpc/solver/shooting.hpp"
#include "support/problems.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;
using test::Problem;
using test::random_vector;

// matrix and adjoint evaluate the same sums in another order: rounding only
constexpr double kSameResidual = 1e-9;
// C/GMRES's increment, and a central-difference step whose truncation error (~1e-8) and
// rounding error (~1e-12) are both far below the forward difference's O(h) + O(ε/h)
constexpr double kH = 1e-8;
constexpr double kReferenceStep = 1e-4;
// measured worst 1e-4 (FD adjoint on chain32): a Krylov basis this accurate is what GMRES needs
constexpr double kFrechetAccuracy = 1e-3;

double rel(const VecX<double>& a, const VecX<double>& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

class OcpModes : public ::testing::TestWithParam<std::tuple<std::string, Formulation>> {};

TEST_P(OcpModes, MatrixAndAdjointGiveTheSameResidual) {
  const auto& [path, formulation] = GetParam();
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 10;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    Shooting matrix(p.model, formulation, DerivativeMode::kMatrix, paper_weights(n, 1e-3),
               VecX<double>::Zero(n), N);
    Shooting adjoint(p.model, formulation, DerivativeMode::kAdjoint, paper_weights(n, 1e-3),
                VecX<double>::Zero(n), N);
    const VecX<double> U = random_vector(rng, N * n, 5.0), q0 = random_vector(rng, n, 2.0),
                       v0 = random_vector(rng, n, 1.0);
    VecX<double> F1(N * n), F2(N * n);
    matrix.residual(U, q0, v0, 0.3, F1);
    adjoint.residual(U, q0, v0, 0.3, F2);
    EXPECT_LE(rel(F1, F2), kSameResidual);
  }
}

// C/GMRES's Fréchet product (F(U + hW) − F(U))/h, h = 1e-8, against a central difference with
// a step large enough to be free of rounding: the rounding noise of F, divided by h, must stay
// small. On the ill-conditioned 32-link chain (cond M ≈ 1e6) the matrix-mode FD problem is
// the exception (from forming ∂q̈/∂q before multiplying by γ; docs/dynamics.md), so it is
// checked on the well-conditioned models only.
TEST(OcpFrechetProduct, ForwardDifferenceWithH1e8IsAccurate) {
  for (const std::string name : {"arm4", "tree", "chain32"}) {
    const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/" + name + ".xml");
    const int n = p.model.n, N = 25;
    std::mt19937 rng(3);
    const VecX<double> U = random_vector(rng, N * n, 0.5), q0 = random_vector(rng, n, 0.3),
                       v0 = random_vector(rng, n, 0.5);
    const VecX<double> W = random_vector(rng, N * n, 1.0).normalized();
    for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      for (const DerivativeMode d : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
        if (name == "chain32" && f == Formulation::kForwardDynamics && d == DerivativeMode::kMatrix) continue;
        SCOPED_TRACE(name + " " + to_string(f) + " " + to_string(d));
        Shooting ocp(p.model, f, d, paper_weights(n, 0.0), VecX<double>::Zero(n), N);
        VecX<double> F0(N * n), Fp(N * n), Fm(N * n);
        ocp.residual(U, q0, v0, 0.1, F0);
        ocp.residual(U + kH * W, q0, v0, 0.1, Fp);
        const VecX<double> frechet = (Fp - F0) / kH;
        ocp.residual(U + kReferenceStep * W, q0, v0, 0.1, Fp);
        ocp.residual(U - kReferenceStep * W, q0, v0, 0.1, Fm);
        const VecX<double> reference = (Fp - Fm) / (2 * kReferenceStep);
        EXPECT_LE((frechet - reference).norm() / reference.norm(), kFrechetAccuracy);
      }
    }
  }
}

// Torque limits (formulations.md §Torque limits) on some joints, others unbounded, torques on both sides of the
// bounds: matrix and adjoint modes and the SIMD lanes agree with limits as without.
TorqueLimits some_limits(int n, double bound) {
  const double inf = std::numeric_limits<double>::infinity();
  TorqueLimits limits{VecX<double>::Constant(n, -inf), VecX<double>::Constant(n, inf)};
  for (int j = 0; j < n; j += 3) {
    limits.lower[j] = -bound;
    limits.upper[j] = 0.5 * bound;  // ū ≠ 0
  }
  return limits;
}

VecX<double> limited_unknowns(std::mt19937& rng, const OcpProblem& problem, int N, double input) {
  const int n = problem.n(), m = problem.m(), sd = problem.stage_dim();
  VecX<double> U(N * sd);
  for (int i = 0; i < N; ++i) {
    U.segment(i * sd, n) = random_vector(rng, n, input);
    U.segment(i * sd + n, m) = random_vector(rng, m, 0.01, 5.0);
    U.segment(i * sd + n + m, m) = random_vector(rng, m, -1.0, 10.0);
  }
  return U;
}

// Every variant whose single-shooting stages are independent runs them in SIMD lanes: ID with
// adjoints (RNEA and its adjoint) and in matrix mode (RNEA derivatives and the products with them),
// FD in matrix mode (the stage derivatives after the rollout). Stage by stage gives the same
// residual, with and without torque limits.
TEST(OcpStageBatching, SimdLanesGiveTheSameResidualAsStageByStage) {
  const std::pair<Formulation, DerivativeMode> variants[] = {
      {Formulation::kInverseDynamics, DerivativeMode::kAdjoint},
      {Formulation::kInverseDynamics, DerivativeMode::kMatrix},
      {Formulation::kForwardDynamics, DerivativeMode::kMatrix}};
  for (const std::string name : {"arm4", "tree", "chain32"}) {
    const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/" + name + ".xml");
    const int n = p.model.n;
    for (const auto& [f, mode] : variants) {
      for (const bool limited : {false, true}) {
        const TorqueLimits limits = limited ? some_limits(n, 5.0) : TorqueLimits{};
        // N not a multiple of the lane count exercises the padded last group
        for (int N : {1, 2, 7, 25}) {
          SCOPED_TRACE(name + " " + to_string(f) + " " + to_string(mode) + (limited ? " limits" : "") +
                       " N=" + std::to_string(N));
          std::mt19937 rng(static_cast<unsigned>(N));
          Shooting lanes(p.model, f, mode, paper_weights(n, 1e-3), VecX<double>::Zero(n), N, limits);
          Shooting single(p.model, f, mode, paper_weights(n, 1e-3), VecX<double>::Zero(n), N, limits);
          single.set_stage_batching(false);
          ASSERT_TRUE(lanes.stage_batching());
          ASSERT_FALSE(single.stage_batching());
          const double input = 5.0;  // FD: torques on both sides of the bounds [−5, 2.5]
          const VecX<double> U = limited_unknowns(rng, lanes.problem(), N, input);
          const VecX<double> q0 = random_vector(rng, n, 2.0), v0 = random_vector(rng, n, 1.0);
          VecX<double> F1(lanes.dim()), F2(lanes.dim()), F3(lanes.dim());
          lanes.residual(U, q0, v0, 0.3, F1);
          single.residual(U, q0, v0, 0.3, F2);
          ASSERT_TRUE(F2.allFinite());
          EXPECT_LE(rel(F1, F2), kSameResidual);
          // the lanes' results do not outlive the evaluation: with lanes off, another point is
          // evaluated afresh, as stage by stage
          lanes.set_stage_batching(false);
          const VecX<double> U2 = limited_unknowns(rng, lanes.problem(), N, input);
          lanes.residual(U2, q0, v0, 0.3, F1);
          single.residual(U2, q0, v0, 0.3, F3);
          EXPECT_EQ(F1, F3);
        }
      }
    }
  }
}

TEST(OcpTorqueLimits, MatrixAdjointAndLanesGiveTheSameResidual) {
  for (const std::string name : {"arm4", "tree", "chain32"}) {
    const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/" + name + ".xml");
    const int n = p.model.n;
    const TorqueLimits limits = some_limits(n, 5.0);
    for (const int N : {1, 7}) {
      for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
        SCOPED_TRACE(name + " " + to_string(f) + " N=" + std::to_string(N));
        std::mt19937 rng(static_cast<unsigned>(N));
        Shooting matrix(p.model, f, DerivativeMode::kMatrix, paper_weights(n, 1e-3), VecX<double>::Zero(n), N, limits);
        Shooting adjoint(p.model, f, DerivativeMode::kAdjoint, paper_weights(n, 1e-3), VecX<double>::Zero(n), N, limits);
        Shooting single(p.model, f, DerivativeMode::kAdjoint, paper_weights(n, 1e-3), VecX<double>::Zero(n), N, limits);
        single.set_stage_batching(false);
        ASSERT_EQ(adjoint.stage_batching(), f == Formulation::kInverseDynamics);
        ASSERT_EQ(matrix.problem().m(), (n + 2) / 3);
        ASSERT_EQ(matrix.dim(), N * (n + 2 * matrix.problem().m()));
        // FD inputs are torques: ±10 straddles the bounds [−5, 2.5]; ID accelerations of ±5 give
        // torques on both sides too
        const VecX<double> U = limited_unknowns(rng, matrix.problem(), N, f == Formulation::kForwardDynamics ? 10.0 : 5.0);
        const VecX<double> q0 = random_vector(rng, n, 2.0), v0 = random_vector(rng, n, 1.0);
        VecX<double> F1(matrix.dim()), F2(matrix.dim()), F3(matrix.dim());
        matrix.residual(U, q0, v0, 0.3, F1);
        adjoint.residual(U, q0, v0, 0.3, F2);
        single.residual(U, q0, v0, 0.3, F3);
        EXPECT_LE(rel(F1, F2), kSameResidual);
        EXPECT_LE(rel(F3, F2), kSameResidual);
      }
    }
  }
}

// No limits, or ±∞ on every joint: no dummy inputs, and the residual of today to the bit.
TEST(OcpTorqueLimits, UnboundedJointsAddNothing) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/tree.xml");
  const int n = p.model.n, N = 7;
  const double inf = std::numeric_limits<double>::infinity();
  const TorqueLimits open{VecX<double>::Constant(n, -inf), VecX<double>::Constant(n, inf)};
  std::mt19937 rng(5);
  const VecX<double> U = random_vector(rng, N * n, 5.0), q0 = random_vector(rng, n, 2.0),
                     v0 = random_vector(rng, n, 1.0);
  for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    for (const DerivativeMode d : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
      Shooting none(p.model, f, d, paper_weights(n, 1e-3), VecX<double>::Zero(n), N);
      Shooting unbounded(p.model, f, d, paper_weights(n, 1e-3), VecX<double>::Zero(n), N, open);
      EXPECT_EQ(none.problem().m(), 0);
      EXPECT_EQ(unbounded.problem().m(), 0);
      EXPECT_EQ(unbounded.stage_dim(), n);
      EXPECT_EQ(unbounded.dim(), N * n);
      VecX<double> F1(N * n), F2(N * n);
      none.residual(U, q0, v0, 0.4, F1);
      unbounded.residual(U, q0, v0, 0.4, F2);
      EXPECT_EQ(F1, F2);
    }
  }
}

// the excess of stage torques over their bounds, per bounded joint only, NaN reported
TEST(OcpTorqueLimits, ViolationIsTheLargestExcessOverTheBounds) {
  const double inf = std::numeric_limits<double>::infinity();
  const TorqueLimits limits{(VecX<double>(3) << -10, -inf, 0).finished(), (VecX<double>(3) << 10, inf, 4).finished()};
  const TorqueBounds bounds(limits, VecX<double>::Constant(3, 1e-3), 3);
  MatX<double> u(3, 2);
  u << 9, -10.5,  // joint 0: inside, then 0.5 below
      1e6, -1e6,  // joint 1: unbounded
      4.25, 1;    // joint 2: 0.25 above
  EXPECT_DOUBLE_EQ(bounds.violation(u), 0.5);
  u(0, 1) = 0;
  EXPECT_DOUBLE_EQ(bounds.violation(u), 0.25);
  u(2, 0) = 2;
  EXPECT_EQ(bounds.violation(u), 0.0);  // inside everywhere
  u(2, 1) = std::nan("");
  EXPECT_TRUE(std::isnan(bounds.violation(u)));
}

TEST(OcpTorqueLimits, BadLimitsAreRefusedNamingTheJoint) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  auto refused = [&](TorqueLimits limits, const std::string& needle, double R = 1e-4) {
    SCOPED_TRACE(needle);
    OcpWeights w = paper_weights(4);
    w.R[2] = R;
    try {
      OcpProblem problem(p.model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, w, VecX<double>::Zero(4), 5,
                         limits);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  const TorqueLimits good{VecX<double>::Constant(4, -1.0), VecX<double>::Constant(4, 1.0)};
  TorqueLimits bad = good;
  bad.lower.resize(3);
  refused(bad, "expected 4 each");
  bad = good;
  bad.upper[1] = nan;
  refused(bad, "joint 1");
  bad = good;
  bad.upper[2] = inf;  // one-sided
  refused(bad, "joint 2");
  bad = good;
  bad.lower[3] = 1.0;  // lower = upper
  refused(bad, "joint 3");
  refused(good, "joint 2 is [-1, 1]: a bounded joint needs R > 0", 0.0);
}

// The limits' rows are capped at the input's block (torque_limits.hpp): s_j = min(R_j, C_j)/Δ_j
// with C the block's diagonal, here recomputed from MuJoCo's mass matrix (mj_fullM). ID's cap
// binds where R_j exceeds (MᵀRM)_jj + Q_a + c_j; FD's never does (C_j ≥ R_j). The constraint
// stays the same set: at a torque inside its range the consistent (d, ρ) zero ∂H/∂d and ∂H/∂ρ.
TEST(OcpTorqueLimits, TheLimitsRowsAreCappedAtTheInputsBlock) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const int n = 4, N = 25;
  const double Tf = 0.5, dtau = Tf / N;
  const VecX<double> q_ref = (VecX<double>(n) << 0.3, -0.7, 1.1, 0.4).finished();
  const TorqueLimits limits{(VecX<double>(n) << -20, -8, -3, -1).finished(), (VecX<double>(n) << 20, 6, 3, 2).finished()};
  OcpWeights w = paper_weights(n, 1e-4);
  w.Qq.setConstant(100);
  w.Qv.setConstant(10);
  w.R = (VecX<double>(n) << 1e-3, 1e-2, 30, 300).finished();  // the last one(s) above ID's block
  mj::Reference ref(p.m.get());
  const MatX<double> M = ref.mass_matrix(q_ref), Minv = M.inverse();
  const VecX<double> c = dtau * (w.Qq * (Tf * Tf * Tf / 3) + w.Qv * Tf);
  for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    SCOPED_TRACE(to_string(f));
    OcpProblem problem(p.model, f, DerivativeMode::kAdjoint, w, q_ref, N, limits);
    const VecX<double> plain = problem.torque_bounds().scale();
    problem.cap_limit_rows(Tf);
    const TorqueBounds& b = problem.torque_bounds();
    VecX<double> C(n);
    for (int j = 0; j < n; ++j) {
      if (f == Formulation::kInverseDynamics) {
        C[j] = w.Qa[j] + c[j];
        for (int k = 0; k < n; ++k) C[j] += M(k, j) * M(k, j) * w.R[k];
      } else {
        C[j] = w.R[j];
        for (int k = 0; k < n; ++k) C[j] += Minv(k, j) * Minv(k, j) * c[k];
      }
    }
    EXPECT_LE((problem.input_block_diagonal(Tf) - C).cwiseAbs().maxCoeff(), 1e-10 * C.maxCoeff());
    int capped = 0, above = 0;
    for (int j = 0; j < n; ++j) {
      above += w.R[j] > C[j];
      const double Delta = limits.upper[j] - limits.lower[j];
      EXPECT_DOUBLE_EQ(plain[j], w.R[j] / Delta) << "joint " << j;
      EXPECT_NEAR(b.scale()[j], std::min(w.R[j], C[j]) / Delta, 1e-12 * plain[j]) << "joint " << j;
      capped += b.scale()[j] < plain[j];
    }
    EXPECT_EQ(capped, above);
    if (f == Formulation::kInverseDynamics) {
      EXPECT_GE(capped, 1) << "R of the last joint lies above ID's block";
    } else {
      EXPECT_EQ(capped, 0) << "FD's block holds R itself";
    }
    VecX<double> d(n), rho(n), H_d(n), H_rho(n);
    const VecX<double> inside = (VecX<double>(n) << 15, -7, 0.5, 1.9).finished();
    b.consistent_dummy(inside, d, rho);
    b.dummy_gradients(inside, d, rho, H_d, H_rho);
    for (int j = 0; j < n; ++j) {
      EXPECT_LE(std::abs(H_d[j]), 1e-14 * b.r_d()[j]) << "joint " << j;
      EXPECT_LE(std::abs(H_rho[j]), 1e-12 * b.scale()[j] * b.half_range()[j] * b.half_range()[j]) << "joint " << j;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, OcpModes,
    ::testing::Combine(::testing::Values(std::string(IDMPC_SOURCE_DIR "/mjcf/arm4.xml"),
                                         std::string(IDMPC_SOURCE_DIR "/mjcf/tree.xml"),
                                         // ill-conditioned M (cond ~ 1e6): F must stay smooth
                                         std::string(IDMPC_SOURCE_DIR "/mjcf/chain32.xml")),
                       ::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics)));

}  // namespace
}  // namespace idmpc
