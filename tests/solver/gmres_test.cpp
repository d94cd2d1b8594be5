// Matrix-free GMRES on known dense systems: exact in dim iterations, optimal over nested
// Krylov spaces (residual non-increasing in kmax), honest about its residual, and cheap when
// the initial guess is already the solution.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <string>

#include <Eigen/LU>

#include "idmpc/solver/gmres.hpp"

namespace idmpc {
namespace {

constexpr int kDim = 30;
// A = 3 I + G/√dim with G standard normal: G/√dim has its spectrum in the unit disc (circular
// law), so A's eigenvalues lie near the disc |z − 3| ≤ 1 and cond(A) ≈ 2: GMRES converges at
// about (1/3)^k and the LU reference is accurate to ~1e-15.
constexpr double kShift = 3.0;
// kmax = dim: GMRES is a direct method up to rounding, ‖b − A x‖/‖b‖ ~ dim·ε·cond(A) ≈ 1e-14
constexpr double kSolvedResidual = 1e-10;
// x against the LU solution: the residual bound times cond(A) ≈ 2, with room
constexpr double kSolutionMatch = 1e-9;
// the Givens estimate |g_k| and the true ‖b − A x‖ differ by the rounding of the Arnoldi
// process and of x += V y, a few ε·‖b‖·dim
constexpr double kEstimateMatch = 1e-10;
// GMRES minimizes over nested Krylov spaces; rounding may reorder residuals at the ε level
constexpr double kMonotoneSlack = 1e-12;

MatX<double> random_system(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  MatX<double> A(kDim, kDim);
  for (int i = 0; i < kDim; ++i) {
    for (int j = 0; j < kDim; ++j) A(i, j) = g(rng) / std::sqrt(static_cast<double>(kDim));
  }
  A.diagonal().array() += kShift;
  return A;
}

VecX<double> random_rhs(unsigned seed) {
  std::mt19937 rng(seed + 1000);
  std::normal_distribution<double> g(0.0, 1.0);
  VecX<double> b(kDim);
  for (int i = 0; i < kDim; ++i) b[i] = g(rng);
  return b;
}

// out = A·in, the matrix-free interface the solver sees
auto product(const MatX<double>& A) {
  return [&A](const Eigen::Ref<const VecX<double>>& in, Eigen::Ref<VecX<double>> out) { out = A * in; };
}

class GmresSeeds : public ::testing::TestWithParam<unsigned> {};

TEST_P(GmresSeeds, FullKrylovSpaceSolvesTheSystem) {
  const unsigned seed = GetParam();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const MatX<double> A = random_system(seed);
  const VecX<double> b = random_rhs(seed);
  const VecX<double> x_lu = A.partialPivLu().solve(b);

  Gmres gmres(kDim, kDim);
  VecX<double> x = VecX<double>::Zero(kDim);
  const int iterations = gmres.solve(product(A), b, x);
  EXPECT_GE(iterations, 1);
  EXPECT_LE(iterations, kDim);
  EXPECT_LE((b - A * x).norm() / b.norm(), kSolvedResidual);
  EXPECT_LE(gmres.residual_norm() / b.norm(), kSolvedResidual);
  EXPECT_LE((x - x_lu).norm() / x_lu.norm(), kSolutionMatch);
}

TEST_P(GmresSeeds, ResidualIsNonIncreasingInKmaxAndReportedHonestly) {
  const unsigned seed = GetParam();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const MatX<double> A = random_system(seed);
  const VecX<double> b = random_rhs(seed);
  double previous = b.norm();  // kmax = 0 would leave x = 0
  for (int kmax = 1; kmax < kDim; ++kmax) {
    SCOPED_TRACE("kmax " + std::to_string(kmax));
    Gmres gmres(kDim, kmax);
    VecX<double> x = VecX<double>::Zero(kDim);
    gmres.solve(product(A), b, x);
    const double actual = (b - A * x).norm();
    EXPECT_NEAR(gmres.residual_norm(), actual, kEstimateMatch * b.norm());
    EXPECT_LE(actual, previous + kMonotoneSlack * b.norm());
    previous = actual;
  }
  // the fast convergence promised by the spectrum: (1/3)^k, checked loosely at k = 10
  Gmres gmres(kDim, 10);
  VecX<double> x = VecX<double>::Zero(kDim);
  gmres.solve(product(A), b, x);
  EXPECT_LE((b - A * x).norm() / b.norm(), 1e-3);
}

TEST_P(GmresSeeds, WarmStartFromTheSolutionReturnsAtOnce) {
  const unsigned seed = GetParam();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const MatX<double> A = random_system(seed);
  const VecX<double> x_exact = random_rhs(seed);
  // b made by the same product the solver uses, so b − A x is exactly zero
  VecX<double> b(kDim);
  product(A)(x_exact, b);
  Gmres gmres(kDim, 10);
  VecX<double> x = x_exact;
  int calls = 0;
  auto counted = [&](const Eigen::Ref<const VecX<double>>& in, Eigen::Ref<VecX<double>> out) {
    ++calls;
    out = A * in;
  };
  EXPECT_EQ(gmres.solve(counted, b, x), 0);
  EXPECT_EQ(calls, 1);  // the initial residual only
  EXPECT_EQ(gmres.residual_norm(), 0.0);
  EXPECT_EQ(x, x_exact);
}

TEST_P(GmresSeeds, WarmStartNeverMakesTheGuessWorse) {
  const unsigned seed = GetParam();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const MatX<double> A = random_system(seed);
  const VecX<double> b = random_rhs(seed);
  VecX<double> x = A.partialPivLu().solve(b) + 1e-3 * random_rhs(seed + 7);
  const double before = (b - A * x).norm();
  Gmres gmres(kDim, 3);
  gmres.solve(product(A), b, x);
  EXPECT_LE((b - A * x).norm(), before);
}

INSTANTIATE_TEST_SUITE_P(Seeds, GmresSeeds, ::testing::Values(1u, 2u, 3u, 4u, 5u));

TEST(Gmres, ZeroRightHandSideLeavesZero) {
  const MatX<double> A = random_system(9);
  Gmres gmres(kDim, 5);
  VecX<double> x = VecX<double>::Zero(kDim);
  EXPECT_EQ(gmres.solve(product(A), VecX<double>::Zero(kDim), x), 0);
  EXPECT_TRUE(x.isZero(0.0));
}

TEST(Gmres, IdentityIsSolvedInOneIteration) {
  const MatX<double> I = MatX<double>::Identity(kDim, kDim);
  const VecX<double> b = random_rhs(11);
  Gmres gmres(kDim, 10);
  VecX<double> x = VecX<double>::Zero(kDim);
  EXPECT_EQ(gmres.solve(product(I), b, x), 1);  // happy breakdown after one Arnoldi step
  EXPECT_LE((x - b).norm() / b.norm(), kSolvedResidual);
}

void expect_invalid(int dim, int kmax, const std::string& needle) {
  SCOPED_TRACE("dim " + std::to_string(dim) + ", kmax " + std::to_string(kmax));
  try {
    Gmres gmres(dim, kmax);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

TEST(Gmres, RejectsKmaxBelowOne) { expect_invalid(kDim, 0, "kmax"); }

TEST(Gmres, RejectsNegativeKmax) { expect_invalid(kDim, -1, "kmax"); }

TEST(Gmres, RejectsEmptyDimension) { expect_invalid(0, 5, "dimension"); }

}  // namespace
}  // namespace idmpc
