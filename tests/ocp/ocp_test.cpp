// The two formulations and two derivative modes: same residual across modes, the residual is
// the gradient of the discretized cost, and the two formulations agree where they must.
#include <gtest/gtest.h>

#include <random>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/ocp/ocp.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

// matrix and adjoint evaluate the same sums in another order: rounding only
constexpr double kSameResidual = 1e-9;

struct Problem {
  mj::ModelPtr m;
  Model model;
};

Problem load(const std::string& path) {
  Problem p{mj::load_model(path), {}};
  p.model = mj::import_model(p.m.get(), path).model;
  return p;
}

OcpWeights paper_weights(int n, double Qa) {
  return {VecX<double>::Constant(n, 1.0), VecX<double>::Constant(n, 0.1),
          VecX<double>::Constant(n, Qa), VecX<double>::Constant(n, 1e-4)};
}

VecX<double> random_vector(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  VecX<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng);
  return x;
}

double rel(const VecX<double>& a, const VecX<double>& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

class OcpModes : public ::testing::TestWithParam<std::tuple<std::string, Formulation>> {};

TEST_P(OcpModes, MatrixAndAdjointGiveTheSameResidual) {
  const auto& [path, formulation] = GetParam();
  const Problem p = load(path);
  const int n = p.model.n, N = 10;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    Ocp matrix(p.model, formulation, DerivativeMode::kMatrix, paper_weights(n, 1e-3),
               VecX<double>::Zero(n), N);
    Ocp adjoint(p.model, formulation, DerivativeMode::kAdjoint, paper_weights(n, 1e-3),
                VecX<double>::Zero(n), N);
    const VecX<double> U = random_vector(rng, N * n, 5.0), q0 = random_vector(rng, n, 2.0),
                       v0 = random_vector(rng, n, 1.0);
    VecX<double> F1(N * n), F2(N * n);
    matrix.residual(U, q0, v0, 0.3, F1);
    adjoint.residual(U, q0, v0, 0.3, F2);
    EXPECT_LE(rel(F1, F2), kSameResidual);
  }
}

TEST(OcpStageBatching, SimdLanesGiveTheSameResidualAsStageByStage) {
  for (const std::string path : {IDMPC_SOURCE_DIR "/mjcf/arm4.xml", IDMPC_SOURCE_DIR "/mjcf/tree.xml"}) {
    const Problem p = load(path);
    const int n = p.model.n;
    // N not a multiple of the lane count exercises the padded last group
    for (int N : {1, 7, 25}) {
      SCOPED_TRACE(path + " N=" + std::to_string(N));
      std::mt19937 rng(static_cast<unsigned>(N));
      Ocp lanes(p.model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, paper_weights(n, 1e-3),
                VecX<double>::Zero(n), N);
      Ocp single(p.model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, paper_weights(n, 1e-3),
                 VecX<double>::Zero(n), N);
      single.set_stage_batching(false);
      ASSERT_TRUE(lanes.stage_batching());
      ASSERT_FALSE(single.stage_batching());
      const VecX<double> U = random_vector(rng, N * n, 5.0), q0 = random_vector(rng, n, 2.0),
                         v0 = random_vector(rng, n, 1.0);
      VecX<double> F1(N * n), F2(N * n);
      lanes.residual(U, q0, v0, 0.4, F1);
      single.residual(U, q0, v0, 0.4, F2);
      EXPECT_LE(rel(F1, F2), kSameResidual);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, OcpModes,
    ::testing::Combine(::testing::Values(std::string(IDMPC_SOURCE_DIR "/mjcf/arm4.xml"),
                                         std::string(IDMPC_SOURCE_DIR "/mjcf/tree.xml")),
                       ::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics)));

}  // namespace
}  // namespace idmpc
