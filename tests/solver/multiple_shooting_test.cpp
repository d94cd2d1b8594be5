// Multiple shooting with condensing (formulations.md §Multiple shooting) on the four controllers (FD/ID × matrix/adjoint),
// with and without torque limits: the residual at stored trajectories is that of single shooting
// when they are the rollout; the condensed sweep retrieves stored trajectories from their
// defects; the condensed C/GMRES direction solves the uncondensed continuation system (states and
// costates as unknowns, its Jacobian by central differences); both schemes converge to the same
// solution from the same start; an update costs one evaluation more than single shooting.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <tuple>

#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/shooting.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;
using test::Problem;
using test::random_vector;

const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";

// rollout and costate sweep against the same quantities recomputed stage by stage: both are sums
// of the same terms in another order, so they agree to a few ulps of the trajectory's magnitude
constexpr double kRounding = 1e-11;
// see cgmres_test: h = 1e-8 forward differences carry rounding ε‖F‖/h ≈ 1e-7·‖J‖ (more in
// matrix mode and for FD), the central-difference Jacobian 1e-10; a backward-error check
constexpr double kContinuationSolved = 1e-5;
// Newton–GMRES with a full Krylov space on the frozen problem: quadratic convergence stops at the
// forward-difference floor ε‖F‖/h·cond(∂F/∂U), measured 6e-13 … 3e-9 for ID and 5e-8 … 6e-7 for
// FD after 12 steps (FD's ∂F/∂U is the worse conditioned, see cgmres_test)
constexpr double kConvergedId = 1e-7;
constexpr double kConvergedFd = 5e-6;
// the two converged solutions differ by cond(∂F/∂U)·floor (cond ≈ 2.5e5 for FD)
constexpr double kSameSolution = 1e-5;

using Variant = std::tuple<Formulation, DerivativeMode, bool>;  // with torque limits
std::string variant_name(const ::testing::TestParamInfo<Variant>& info) {
  const auto& [f, d, limited] = info.param;
  return to_string(f) + "_" + to_string(d) + (limited ? "_limits" : "");
}

// ±20 N m on joints 0 and 2 of arm4
TorqueLimits arm4_limits() {
  const double inf = std::numeric_limits<double>::infinity();
  return TorqueLimits{(VecX<double>(4) << -20, -inf, -20, -inf).finished(),
                      (VecX<double>(4) << 20, inf, 20, inf).finished()};
}

class MultipleShooting : public ::testing::TestWithParam<Variant> {
 protected:
  MultipleShooting() : p_(load_problem(kArm4)) {}
  Shooting make(int N, double R = 1e-4) const {
    const auto& [f, d, limited] = GetParam();
    OcpWeights w = paper_weights(4);
    w.R.setConstant(R);
    return Shooting(p_.model, f, d, w, VecX<double>::Zero(4), N, limited ? arm4_limits() : TorqueLimits{});
  }
  // a solution-like U: random inputs, positive dummies and multipliers
  VecX<double> random_U(const Shooting& ocp, std::mt19937& rng) const {
    const int n = ocp.n(), m = ocp.problem().m(), sd = ocp.stage_dim();
    VecX<double> U(ocp.dim());
    for (int i = 0; i < ocp.N(); ++i) {
      U.segment(i * sd, n) = random_vector(rng, n, 3.0);
      if (m > 0) U.segment(i * sd + n, 2 * m) = random_vector(rng, 2 * m, 0.5, 2.0);
    }
    return U;
  }
  Problem p_;
};

// a mid-swing state of arm4 (the first link half-way, moving)
const VecX<double> kQ = (VecX<double>(4) << -1.5, 0.25, 0.27, -0.23).finished();
const VecX<double> kV = (VecX<double>(4) << 2.0, -1.0, 0.5, 0.3).finished();

double scale(const ShootingTrajectory& x) { return std::max(1.0, x.max_abs()); }

// the unknown columns 1 … N of every stored trajectory moved by up to ±size: nonzero defects
ShootingTrajectory perturbed(ShootingTrajectory X, double size, std::mt19937& rng) {
  for (MatX<double>* x : {&X.q, &X.v, &X.lmd, &X.gmm}) {
    const Eigen::Index N = x->cols() - 1;
    x->rightCols(N) += MatX<double>::NullaryExpr(x->rows(), N, [&] { return random_vector(rng, 1, size)[0]; });
  }
  return X;
}

TEST_P(MultipleShooting, AtTheRolloutTheResidualIsSingleShootingsWithZeroDefects) {
  const int N = 6;
  Shooting ocp = make(N);
  std::mt19937 rng(7);
  const VecX<double> U = random_U(ocp, rng);
  VecX<double> F(ocp.dim()), Fm(ocp.dim());
  ocp.residual(U, kQ, kV, 0.3, F);
  const ShootingTrajectory rollout = ocp.trajectory();
  ShootingDefects E;
  E.resize(4, N);
  ocp.residual_at(U, rollout, kQ, kV, 0.3, Fm, E);
  EXPECT_LE(std::sqrt(E.squared_norm()), kRounding * scale(rollout));
  EXPECT_LE((Fm - F).norm(), kRounding * std::max(1.0, F.norm()));
}

TEST_P(MultipleShooting, TheCondensedSweepRetrievesStoredTrajectoriesFromTheirDefects) {
  const int N = 6;
  Shooting ocp = make(N);
  std::mt19937 rng(11);
  const VecX<double> U = random_U(ocp, rng);
  VecX<double> F(ocp.dim()), Fc(ocp.dim());
  ocp.residual(U, kQ, kV, 0.3, F);
  // stored trajectories well away from the rollout
  const ShootingTrajectory X = perturbed(ocp.trajectory(), 0.3, rng);
  ShootingDefects E;
  E.resize(4, N);
  ocp.residual_at(U, X, kQ, kV, 0.3, F, E);
  ASSERT_GT(std::sqrt(E.squared_norm()), 0.1);
  ocp.residual(U, kQ, kV, 0.3, Fc, &E);
  const ShootingTrajectory& r = ocp.trajectory();
  const double tol = kRounding * 100 * scale(X);  // the recursion accumulates N stages of rounding
  EXPECT_LE((r.q.rightCols(N) - X.q.rightCols(N)).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((r.v.rightCols(N) - X.v.rightCols(N)).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((r.lmd.rightCols(N) - X.lmd.rightCols(N)).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((r.gmm.rightCols(N) - X.gmm.rightCols(N)).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((Fc - F).norm(), 100 * kRounding * std::max(1.0, F.norm()));
}

// At stored trajectories every stage is independent; every variant evaluates stages in SIMD lanes
// (ID: stage dynamics and products; FD matrix: the stage derivatives; FD adjoint: the whole stage,
// at the stored costates). N = 7 leaves a padded group.
TEST_P(MultipleShooting, TheResidualAtStoredTrajectoriesIsTheSameInLanesAndStageByStage) {
  const auto& [formulation, mode, limited] = GetParam();
  const int N = 7;
  Shooting lanes = make(N), single = make(N);
  single.set_stage_batching(false);
  EXPECT_EQ(lanes.problem().costate_lanes(),
            formulation == Formulation::kForwardDynamics && mode == DerivativeMode::kAdjoint);
  EXPECT_EQ(lanes.stage_batching(),
            formulation == Formulation::kInverseDynamics || mode == DerivativeMode::kMatrix);
  EXPECT_FALSE(single.problem().costate_lanes() || single.stage_batching());
  std::mt19937 rng(13);
  const VecX<double> U = random_U(lanes, rng);
  VecX<double> F(lanes.dim()), F1(lanes.dim()), F2(lanes.dim());
  single.residual(U, kQ, kV, 0.3, F);
  const ShootingTrajectory X = perturbed(single.trajectory(), 0.2, rng);
  ShootingDefects E1, E2;
  E1.resize(4, N);
  E2.resize(4, N);
  lanes.residual_at(U, X, kQ, kV, 0.3, F1, E1);
  single.residual_at(U, X, kQ, kV, 0.3, F2, E2);
  EXPECT_LE((F1 - F2).norm(), kRounding * std::max(1.0, F2.norm()));
  EXPECT_LE(std::sqrt(ShootingDefects{E1.q - E2.q, E1.v - E2.v, E1.lmd - E2.lmd, E1.gmm - E2.gmm}.squared_norm()),
            kRounding * scale(X));
  // and the products do not outlive the evaluation: single shooting after it is unchanged
  VecX<double> F3(lanes.dim());
  lanes.residual(U, kQ, kV, 0.3, F3);
  EXPECT_LE((F3 - F).norm(), kRounding * std::max(1.0, F.norm()));
}

// The uncondensed continuation system: unknowns Z = (U, q_1…q_N, v_1…v_N, λ_1…λ_N, γ_1…γ_N),
// residual R = (F_U, defects), J Ż = −ζR − (∂R/∂x)ẋ − ∂R/∂t. The condensed update's (U̇, Ẋ)
// must solve it.
TEST_P(MultipleShooting, TheCondensedDirectionSolvesTheUncondensedSystem) {
  const auto& [formulation, mode, limited] = GetParam();
  const int n = 4, N = 4;
  Shooting ocp = make(N);
  Shooting probe = make(N);
  const int dim = ocp.dim(), nz = dim + 4 * n * N;
  CgmresSettings s;
  s.kmax = dim;
  s.shooting = ShootingScheme::kMultiple;
  Cgmres solver(ocp, s);
  const double t = 0.5;  // α = 1: a growing horizon, ∂R/∂t ≠ 0
  solver.initialize(t, kQ, kV);
  // perturbed stored trajectories: nonzero defects
  std::mt19937 rng(3);
  const ShootingTrajectory X = perturbed(solver.trajectory(), 0.05, rng);
  solver.set_trajectory(X);
  VecX<double> U = solver.solution();
  if (limited) {
    // the update makes (d, ρ) consistent with the stage torques first: start from there
    ShootingDefects E;
    E.resize(n, N);
    VecX<double> F(dim);
    probe.residual_at(U, X, kQ, kV, solver.horizon(t), F, E);
    for (int i = 0; i < N; ++i) {
      const int sd = probe.stage_dim(), m = probe.problem().m();
      probe.problem().torque_bounds().consistent_dummy(probe.torques().col(i), U.segment(i * sd + n, m),
                                                       U.segment(i * sd + n + m, m));
    }
    solver.set_solution(U);
  }

  // R(Z, x, t) stacked
  auto pack = [&](const VecX<double>& Uz, const ShootingTrajectory& Xz) {
    VecX<double> z(nz);
    z.head(dim) = Uz;
    int k = dim;
    for (const MatX<double>* x : {&Xz.q, &Xz.v, &Xz.lmd, &Xz.gmm}) {
      z.segment(k, n * N) = x->rightCols(N).reshaped();
      k += n * N;
    }
    return z;
  };
  auto unpack = [&](const VecX<double>& z, VecX<double>& Uz, ShootingTrajectory& Xz) {
    Uz = z.head(dim);
    int k = dim;
    for (MatX<double>* x : {&Xz.q, &Xz.v, &Xz.lmd, &Xz.gmm}) {
      x->rightCols(N).reshaped() = z.segment(k, n * N);
      k += n * N;
    }
  };
  auto R = [&](const VecX<double>& z, const VecX<double>& q, const VecX<double>& v, double tt) {
    VecX<double> Uz;
    ShootingTrajectory Xz = X;
    unpack(z, Uz, Xz);
    VecX<double> F(dim);
    ShootingDefects E;
    E.resize(n, N);
    probe.residual_at(Uz, Xz, q, v, solver.horizon(tt), F, E);
    VecX<double> r(nz);
    r.head(dim) = F;
    r.segment(dim, n * N) = E.q.leftCols(N).reshaped();
    r.segment(dim + n * N, n * N) = E.v.leftCols(N).reshaped();
    r.segment(dim + 2 * n * N, n * N) = E.lmd.rightCols(N).reshaped();
    r.segment(dim + 3 * n * N, n * N) = E.gmm.rightCols(N).reshaped();
    return r;
  };
  const VecX<double> z = pack(U, X);
  const VecX<double> r = R(z, kQ, kV, t);
  const VecX<double> a0 = probe.first_acceleration();
  const double eps = 1e-6;
  const VecX<double> dr =
      (R(z, kQ + eps * kV, kV + eps * a0, t + eps) - R(z, kQ - eps * kV, kV - eps * a0, t - eps)) / (2 * eps);
  const MatX<double> J =
      central_difference_jacobian([&](const VecX<double>& zz) { return R(zz, kQ, kV, t); }, z);
  const VecX<double> rhs = -solver.settings().zeta * r - dr;

  ASSERT_TRUE(solver.update(t, kQ, kV)) << solver.failure();
  EXPECT_NEAR(solver.residual_norm(), r.norm(), 1e-9 * r.norm());
  // the condensed step: U̇ from GMRES, Ẋ from the stored trajectories' move
  const VecX<double> zdot = (pack(solver.solution(), solver.trajectory()) - z) / s.dt;
  EXPECT_LE((zdot.head(dim) - solver.solution_rate()).norm(), 1e-9 * zdot.norm());
  const double normJ = Eigen::JacobiSVD<MatX<double>>(J).singularValues()(0);
  EXPECT_LE((J * zdot - rhs).norm() / (normJ * zdot.norm()), kContinuationSolved)
      << "GMRES iterations " << solver.gmres_iterations();
  // and it is the uncondensed direction itself, within what the backward error allows at this
  // conditioning (cond ≈ 1e2–1e3 for ID, far larger for FD)
  const auto sv = Eigen::JacobiSVD<MatX<double>>(J).singularValues();
  const double cond = sv(0) / sv(sv.size() - 1);
  const VecX<double> exact = J.partialPivLu().solve(rhs);
  EXPECT_LE((zdot - exact).norm(), std::min(1.0, 10 * cond * kContinuationSolved) * exact.norm()) << "cond " << cond;
}

// From the same start — the result of the full-horizon initialization (R = 1e-2) with every input
// moved by up to 5 % for ID, 0.1 % for FD (dummies and multipliers by half that), and the stored
// trajectories those of that start's rollout — Newton–GMRES under each scheme reaches F = 0, at
// the same U; under multiple shooting the defects vanish too. Undamped Newton needs a close
// start, FD the closer: a 1 % kick of FD's torques gives ‖F‖ ≈ 360, from which even a dense
// Newton diverges, and with limits a 10 % kick of (d, ρ) lands ID on the mirrored KKT point
// d < 0, ρ < 0 (under both schemes alike). With exact products (formulations.md §Exact products) both schemes reach the
// same solution as with differences. Measured on the way: multiple shooting's first step
// takes FD from ‖F‖ = 22 to 1e-3, single shooting's to 0.09; for ID the two are alike.
TEST_P(MultipleShooting, BothSchemesConvergeToTheSameSolution) {
  const int N = 10;
  const double kR = 1e-2;
  const VecX<double> q = (VecX<double>(4) << -0.2, 0.1, 0.05, -0.05).finished(), v = VecX<double>::Zero(4);
  VecX<double> solution[2][2];
  const auto& [formulation, mode, limited] = GetParam();
  // exact products in adjoint mode (the matrix mode's dual path: exact_products_test)
  const int products_run = mode == DerivativeMode::kAdjoint ? 2 : 1;
  for (int p = 0; p < products_run; ++p)
  for (const ShootingScheme scheme : {ShootingScheme::kSingle, ShootingScheme::kMultiple}) {
    const Products products = p == 0 ? Products::kDifference : Products::kExact;
    SCOPED_TRACE(to_string(scheme) + " " + to_string(products));
    Shooting ocp = make(N, kR);
    Shooting probe = make(N, kR);
    CgmresSettings s;
    s.alpha = 0;
    s.init_full_horizon = true;
    s.kmax = ocp.dim();
    s.shooting = scheme;
    s.products = products;
    Cgmres solver(ocp, s);
    solver.initialize(0.0, q, v);  // ‖F‖ 1e-10 (ID) … 2e-2 (FD with limits): a start, no more
    const VecX<double> optimum = solver.solution();
    std::mt19937 rng(5);
    const double kick = formulation == Formulation::kForwardDynamics ? 1e-3 : 0.05;
    const int n = 4, m = ocp.problem().m(), sd = ocp.stage_dim();
    VecX<double> start = optimum;
    for (int i = 0; i < N; ++i) {
      start.segment(i * sd, n).array() *= 1 + random_vector(rng, n, kick).array();
      if (m > 0) start.segment(i * sd + n, 2 * m).array() *= 1 + random_vector(rng, 2 * m, kick / 2).array();
    }
    solver.set_solution(start);
    VecX<double> F(ocp.dim());
    probe.residual(start, q, v, s.Tf, F);
    solver.set_trajectory(probe.trajectory());
    ASSERT_GT(F.norm(), 1e-2);
    for (int k = 0; k < 12; ++k) {
      ASSERT_TRUE(solver.newton_step(0.0, q, v)) << "step " << k << ": " << solver.failure();
    }
    ASSERT_TRUE(solver.newton_step(0.0, q, v));
    const double converged = formulation == Formulation::kForwardDynamics ? kConvergedFd : kConvergedId;
    EXPECT_LE(solver.residual_norm(), converged) << "from " << F.norm();
    if (scheme == ShootingScheme::kMultiple) {
      EXPECT_LE(std::sqrt(solver.defects().squared_norm()), converged);
    }
    solution[products == Products::kExact][scheme == ShootingScheme::kMultiple] = solver.solution();
  }
  for (int p = 0; p < products_run; ++p) {
    EXPECT_LE((solution[p][1] - solution[p][0]).norm(), kSameSolution * solution[p][0].norm());
  }
  if (products_run == 2) {
    EXPECT_LE((solution[1][0] - solution[0][0]).norm(), kSameSolution * solution[0][0].norm());
  }
}

TEST_P(MultipleShooting, AnUpdateCostsOneEvaluationMoreThanSingleShooting) {
  const auto& [formulation, mode, limited] = GetParam();
  int evaluations[2];
  for (const ShootingScheme scheme : {ShootingScheme::kSingle, ShootingScheme::kMultiple}) {
    Shooting ocp = make(25);
    CgmresSettings s;
    s.kmax = 5;
    s.shooting = scheme;
    Cgmres solver(ocp, s);
    solver.initialize(0.5, kQ, kV);
    ASSERT_TRUE(solver.update(0.5, kQ, kV));
    EXPECT_EQ(solver.gmres_iterations(), s.kmax);
    evaluations[scheme == ShootingScheme::kMultiple] = solver.evaluations();
  }
  EXPECT_EQ(evaluations[0], 5 + 3 + (limited ? 1 : 0));
  EXPECT_EQ(evaluations[1], evaluations[0] + 1);
}

INSTANTIATE_TEST_SUITE_P(Controllers, MultipleShooting,
                         ::testing::Combine(::testing::Values(Formulation::kForwardDynamics,
                                                              Formulation::kInverseDynamics),
                                            ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint),
                                            ::testing::Bool()),
                         variant_name);

TEST(ShootingNames, ParseAndPrint) {
  for (const ShootingScheme s : {ShootingScheme::kSingle, ShootingScheme::kMultiple}) {
    EXPECT_EQ(parse_shooting(to_string(s)), s);
  }
  try {
    parse_shooting("double");
    ADD_FAILURE() << "accepted 'double'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'double'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace idmpc
