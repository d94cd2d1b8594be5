// The residual is the gradient of the discretized cost (DESIGN §4): with
//   J(U) = Σ_i Δτ L(q_i, v_i, a_i, u_i) + φ(q_N, v_N)
// along the explicit-Euler rollout, the costate recursions are the discrete adjoint, so
//   F_i = (1/Δτ) ∂J/∂U_i
// for both formulations (U = torques for FD, accelerations for ID) and both derivative modes.
// The cost is rolled out here independently, with only RNEA/ABA from the library.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <tuple>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/solver/single_shooting.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;
using test::Problem;
using test::random_vector;

// central differences of a smooth scalar with the ε^(1/3) step: truncation and rounding
// ≈ ε^(2/3) ≈ 4e-11 times the ratio of J's third to first derivatives; measured up to 8e-8
// relative (FD on tree.xml, whose light bodies make J strongly nonlinear in u)
constexpr double kGradientMatch = 1e-6;

// J(U) of DESIGN §4: FD rolls out a_i = FD(q_i, v_i, u_i), ID computes u_i = ID(q_i, v_i, a_i)
double cost(const Model& model, Data& data, Formulation f, const OcpWeights& w, const VecX<double>& q_ref,
            const VecX<double>& U, VecX<double> q, VecX<double> v, double T, int N) {
  const int n = model.n;
  const double dtau = T / N;
  auto phi = [&](const VecX<double>& qi, const VecX<double>& vi) {
    const VecX<double> e = qi - q_ref;
    return 0.5 * e.dot(w.Qq.cwiseProduct(e)) + 0.5 * vi.dot(w.Qv.cwiseProduct(vi));
  };
  double J = 0;
  for (int i = 0; i < N; ++i) {
    VecX<double> a(n), u(n);
    if (f == Formulation::kForwardDynamics) {
      u = U.segment(i * n, n);
      a = aba(model, data, q, v, u);
    } else {
      a = U.segment(i * n, n);
      u = rnea(model, data, q, v, a);
    }
    double L = phi(q, v) + 0.5 * u.dot(w.R.cwiseProduct(u));
    if (f == Formulation::kInverseDynamics) L += 0.5 * a.dot(w.Qa.cwiseProduct(a));
    J += dtau * L;
    const VecX<double> q_next = q + dtau * v;
    v += dtau * a;
    q = q_next;
  }
  return J + phi(q, v);
}

// the stage torques u_i = ID(q_i, v_i, a_i) along the explicit-Euler rollout of accelerations A
VecX<double> torques_of(const Model& model, Data& data, const VecX<double>& A, VecX<double> q,
                        VecX<double> v, double T, int N) {
  const int n = model.n;
  const double dtau = T / N;
  VecX<double> U(N * n);
  for (int i = 0; i < N; ++i) {
    U.segment(i * n, n) = rnea(model, data, q, v, A.segment(i * n, n));
    const VecX<double> q_next = q + dtau * v;
    v += dtau * A.segment(i * n, n);
    q = q_next;
  }
  return U;
}

class OcpGradient
    : public ::testing::TestWithParam<std::tuple<std::string, Formulation, DerivativeMode>> {};

TEST_P(OcpGradient, ResidualIsTheScaledGradientOfTheDiscreteCost) {
  const auto& [path, formulation, mode] = GetParam();
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 6;
  const double T = 0.3;
  Data data(p.model);
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    // distinct positive weights per joint, so that a swapped or transposed weight shows
    const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                       random_vector(rng, n, 1e-3, 1e-2), random_vector(rng, n, 1e-4, 1e-3)};
    const VecX<double> q_ref = random_vector(rng, n, -0.5, 0.5);
    const VecX<double> q0 = random_vector(rng, n, -2.0, 2.0), v0 = random_vector(rng, n, -1.0, 1.0);
    // moderate accelerations, and for FD the torques that produce them: random torques would
    // send light bodies of tree.xml to 1e3 rad/s² and the cost out of finite-difference range
    const VecX<double> A = random_vector(rng, N * n, -3.0, 3.0);
    const VecX<double> U =
        formulation == Formulation::kInverseDynamics ? A : torques_of(p.model, data, A, q0, v0, T, N);
    SingleShooting ocp(p.model, formulation, mode, w, q_ref, N);
    VecX<double> F(N * n);
    ocp.residual(U, q0, v0, T, F);

    const MatX<double> grad = central_difference_jacobian(
        [&](const VecX<double>& X) {
          return VecX<double>::Constant(1, cost(p.model, data, formulation, w, q_ref, X, q0, v0, T, N));
        },
        U);
    const VecX<double> expected = grad.row(0).transpose() / (T / N);
    EXPECT_LE((F - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kGradientMatch)
        << "F        " << F.transpose() << "\nexpected " << expected.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, OcpGradient,
    ::testing::Combine(::testing::Values(std::string(IDMPC_SOURCE_DIR "/mjcf/arm4.xml"),
                                         std::string(IDMPC_SOURCE_DIR "/mjcf/tree.xml")),
                       ::testing::Values(Formulation::kForwardDynamics, Formulation::kInverseDynamics),
                       ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint)),
    [](const auto& info) {
      const std::string path = std::get<0>(info.param);
      const std::string file = path.substr(path.find_last_of('/') + 1);
      return file.substr(0, file.size() - 4) + "_" + to_string(std::get<1>(info.param)) + "_" +
             to_string(std::get<2>(info.param));
    });

// With Q_a = 0 both problems minimize the same cost, in torques U or in accelerations A, and
// the rollout maps A ↦ U(A) one to one (u_i = ID(q_i, v_i, a_i)). By the chain rule, at the same
// trajectory F_ID = (∂U/∂A)ᵀ F_FD: the blocks are M(q_i) on the diagonal and the effect of a_i
// on later torques below it. Hence F_ID,N−1 = M(q_{N−1}) F_FD,N−1 on the last stage, and both
// vanish together, which is what "differ only by the factor M(q_i)" (DESIGN §4) means: the
// same solution, not the same residual away from it.
constexpr double kChainRule = 1e-6;  // central-difference Jacobian of a smooth map, as above
constexpr double kLastStage = 1e-9;  // exact identity up to rounding

TEST(OcpFormulations, IdResidualIsFdResidualThroughTheChainRuleWhenQaIsZero) {
  for (const std::string path : {IDMPC_SOURCE_DIR "/mjcf/arm4.xml", IDMPC_SOURCE_DIR "/mjcf/tree.xml"}) {
    for (DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
      for (unsigned seed = 1; seed <= 3; ++seed) {
        SCOPED_TRACE(path + ", " + to_string(mode) + ", seed " + std::to_string(seed));
        const Problem p = load_problem(path);
        const int n = p.model.n, N = 6;
        const double T = 0.3;
        std::mt19937 rng(seed);
        const OcpWeights w{VecX<double>::Constant(n, 1.0), VecX<double>::Constant(n, 0.1), VecX<double>::Zero(n),
                           VecX<double>::Constant(n, 1e-4)};
        const VecX<double> q_ref = VecX<double>::Zero(n);
        const VecX<double> q0 = random_vector(rng, n, -2.0, 2.0), v0 = random_vector(rng, n, -1.0, 1.0);
        const VecX<double> A = random_vector(rng, N * n, -3.0, 3.0);
        Data data(p.model);
        const VecX<double> U = torques_of(p.model, data, A, q0, v0, T, N);
        SingleShooting fd(p.model, Formulation::kForwardDynamics, mode, w, q_ref, N);
        SingleShooting id(p.model, Formulation::kInverseDynamics, mode, w, q_ref, N);
        VecX<double> Ffd(N * n), Fid(N * n);
        fd.residual(U, q0, v0, T, Ffd);
        id.residual(A, q0, v0, T, Fid);

        const MatX<double> dU_dA = central_difference_jacobian(
            [&](const VecX<double>& X) { return torques_of(p.model, data, X, q0, v0, T, N); }, A);
        const VecX<double> expected = dU_dA.transpose() * Ffd;
        EXPECT_LE((Fid - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kChainRule)
            << "F_ID     " << Fid.transpose() << "\nexpected " << expected.transpose();

        // last stage: the mass matrix at q_{N−1} alone
        VecX<double> q = q0, v = v0;
        for (int i = 0; i < N - 1; ++i) {
          const VecX<double> q_next = q + (T / N) * v;
          v += (T / N) * A.segment(i * n, n);
          q = q_next;
        }
        const VecX<double> last = crba(p.model, data, q) * Ffd.tail(n);
        EXPECT_LE((Fid.tail(n) - last).cwiseAbs().maxCoeff() / std::max(1.0, last.cwiseAbs().maxCoeff()),
                  kLastStage);
      }
    }
  }
}

}  // namespace
}  // namespace idmpc
