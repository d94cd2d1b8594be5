// Under-actuated models (formulations.md §Under-actuation): the residual of both formulations is
// the gradient of the discretized cost, as for the fully actuated ones, with
//   FD: the input the actuators' torques u (n_u), the joints' τ = Sᵀu (passive joints zero);
//   ID: the input the accelerations a (n) and, per passive joint, a multiplier ν of the stage's
//       equality constraint s_E u_E = 0 on its torque u_E = ID_E(q, v, a) − d̂_E,
// each with torque limits on the actuated joints (dummy d and multiplier ρ per bounded joint).
// The augmented cost J(U) is rolled out here with only RNEA/ABA from the library, and
// F = (1/Δτ) ∂J/∂U is checked by central differences in every derivative mode, with stages in
// lanes and one by one, and in dual numbers (exact products) against differences of F.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/solver/shooting.hpp"
#include "support/errors.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::Problem;
using test::random_vector;

constexpr double kGradientMatch = 1e-6;  // as ocp_gradient_test: central differences, ε^(1/3) step

// a 3-link chain whose middle joint has no actuator: a passive joint between two actuated ones
const char* kPassiveMiddle = R"(<mujoco model="passive_middle">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="l0"><joint name="j0" axis="0 1 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.5" size="0.04" mass="1.2"/>
      <body name="l1" pos="0 0 0.5"><joint name="j1" axis="1 0 0" damping="0.02"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0.4" size="0.04" mass="0.8"/>
        <body name="l2" pos="0.1 0 0.4"><joint name="j2" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0.1 0.3" size="0.03" mass="0.5"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="j0" ctrlrange="-20 20" ctrllimited="true"/><motor joint="j2" ctrlrange="-5 5" ctrllimited="true"/></actuator>
</mujoco>)";

Problem passive_middle() {
  mj::ModelPtr m = mj::load_model_from_string(kPassiveMiddle);
  Model model = mj::import_model(m.get(), "passive_middle.xml").model;
  return Problem{std::move(m), std::move(model)};
}

Problem problem_of(const std::string& name) {
  if (name == "passive_middle") return passive_middle();
  return load_problem(IDMPC_SOURCE_DIR "/mjcf/" + name + ".xml");
}

struct ProblemData {
  OcpWeights w;
  VecX<double> q_ref, q0, v0, d_hat;
  TorqueLimits limits;
  MatX<double> P;  ///< terminal weight ½eᵀPe (empty: the diagonal one)
};

// J(U): the stage block is (input, d, ρ, ν) as OcpProblem::stage_dim says
double augmented_cost(const Model& model, Data& data, Formulation f, const ProblemData& s, const TorqueBounds& bounds,
                      double s_E, const VecX<double>& U, double T, int N) {
  const int n = model.n, nu = model.n_actuated(), m = bounds.m();
  const bool fd = f == Formulation::kForwardDynamics;
  const int ni = fd ? nu : n, ne = fd ? 0 : n - nu, sd = ni + 2 * m + ne;
  const double dtau = T / N;
  const VecX<double> zero = VecX<double>::Zero(n);
  const VecX<double> u_ref = rnea(model, data, s.q_ref, zero, zero) - s.d_hat;
  auto phi = [&](const VecX<double>& q, const VecX<double>& v) {
    const VecX<double> e = q - s.q_ref;
    return 0.5 * e.dot(s.w.Qq.cwiseProduct(e)) + 0.5 * v.dot(s.w.Qv.cwiseProduct(v));
  };
  auto terminal = [&](const VecX<double>& q, const VecX<double>& v) {
    if (s.P.size() == 0) return phi(q, v);
    VecX<double> e(2 * n);
    e << q - s.q_ref, v;
    return 0.5 * e.dot(s.P * e);
  };
  VecX<double> q = s.q0, v = s.v0;
  double J = 0;
  for (int i = 0; i < N; ++i) {
    const VecX<double> z = U.segment(i * sd, sd);
    VecX<double> a(n), u = VecX<double>::Zero(n);
    if (fd) {
      for (int k = 0; k < nu; ++k) u[model.actuated_joints[static_cast<size_t>(k)]] = z[k];
      a = aba(model, data, q, v, VecX<double>(u + s.d_hat));
    } else {
      a = z.head(n);
      u = rnea(model, data, q, v, a) - s.d_hat;
    }
    const VecX<double> e = u - u_ref;
    double L = phi(q, v) + 0.5 * e.dot(s.w.R.cwiseProduct(e));
    if (!fd) L += 0.5 * a.dot(s.w.Qa.cwiseProduct(a));
    for (int k = 0; k < m; ++k) {
      const double d = z[ni + k], rho = z[ni + m + k];
      const double du = u[bounds.joints()[static_cast<size_t>(k)]] - bounds.middle()[k];
      L += rho * bounds.scale()[k] * (du * du + d * d - bounds.half_range()[k] * bounds.half_range()[k]) -
           bounds.r_d()[k] * d;
    }
    for (int k = 0; k < ne; ++k) L += s_E * z[ni + 2 * m + k] * u[model.unactuated_joints[static_cast<size_t>(k)]];
    J += dtau * L;
    const VecX<double> q_next = q + dtau * v;
    v += dtau * a;
    q = q_next;
  }
  return J + terminal(q, v);
}

using Case = std::tuple<std::string, Formulation, DerivativeMode>;

class UnderActuation : public ::testing::TestWithParam<Case> {};

TEST_P(UnderActuation, ResidualIsTheGradientOfTheAugmentedCost) {
  const auto& [name, formulation_binding, mode] = GetParam();
  const Formulation formulation = formulation_binding;  // a variable the lambdas may capture (C++17)
  const Problem p = problem_of(name);
  const Model& model = p.model;
  ASSERT_TRUE(model.under_actuated());
  const int n = model.n, N = 5;
  const double T = 0.25;
  Data data(model);
  std::mt19937 rng(7);
  ProblemData s;
  s.w = OcpWeights{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                   random_vector(rng, n, 1e-3, 1e-2), random_vector(rng, n, 1e-2, 1e-1)};
  s.q_ref = random_vector(rng, n, -0.5, 0.5);
  s.q0 = random_vector(rng, n, -1.0, 1.0);
  s.v0 = random_vector(rng, n, -1.0, 1.0);
  s.d_hat = random_vector(rng, n, -0.3, 0.3);
  // limits on every joint: the passive ones' are dropped (no actuator, nothing to bound)
  s.limits.lower = VecX<double>::Constant(n, -30.0);
  s.limits.upper = VecX<double>::Constant(n, 40.0);

  // the terminal cost as an LQR value would be: a symmetric positive definite P
  const MatX<double> L = MatX<double>::Random(2 * n, 2 * n);
  const MatX<double> P = L * L.transpose() + MatX<double>::Identity(2 * n, 2 * n);
  for (const auto& [lanes, with_P] : {std::pair{true, false}, {true, true}, {false, false}, {false, true}}) {
    SCOPED_TRACE(std::string(lanes ? "stages in lanes" : "stage by stage") + (with_P ? ", terminal P" : ""));
    s.P = with_P ? P : MatX<double>();
    Shooting ocp(model, formulation, mode, s.w, s.q_ref, N, s.limits);
    ocp.set_stage_batching(lanes);
    ocp.problem().set_disturbance(s.d_hat);
    ocp.problem().set_terminal_weight(s.P);
    const OcpProblem& problem = ocp.problem();
    const int nu = model.n_actuated(), m = problem.m();
    const bool fd = formulation == Formulation::kForwardDynamics;
    ASSERT_EQ(m, nu) << "only the actuated joints are bounded";
    ASSERT_EQ(problem.input_dim(), fd ? nu : n);
    ASSERT_EQ(problem.equality_dim(), fd ? 0 : n - nu);
    const int sd = problem.stage_dim();
    ASSERT_EQ(sd, problem.input_dim() + 2 * m + problem.equality_dim());
    // inputs that keep the torques inside the limits, dummies and multipliers positive, ν any
    VecX<double> U(N * sd);
    for (int i = 0; i < N; ++i) {
      U.segment(i * sd, problem.input_dim()) = random_vector(rng, problem.input_dim(), fd ? 2.0 : 3.0);
      U.segment(i * sd + problem.input_dim(), 2 * m) = random_vector(rng, 2 * m, 0.5, 2.0);
      U.segment(i * sd + problem.input_dim() + 2 * m, problem.equality_dim()) =
          random_vector(rng, problem.equality_dim(), 3.0);
    }
    VecX<double> F(N * sd);
    ocp.residual(U, s.q0, s.v0, T, F);
    const TorqueBounds bounds = problem.torque_bounds();
    const double s_E = problem.terms().passive_scale();
    const MatX<double> grad = central_difference_jacobian(
        [&](const VecX<double>& X) {
          return VecX<double>::Constant(1, augmented_cost(model, data, formulation, s, bounds, s_E, X, T, N));
        },
        U);
    const VecX<double> expected = grad.row(0).transpose() / (T / N);
    EXPECT_LE((F - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kGradientMatch)
        << "F        " << F.transpose() << "\nexpected " << expected.transpose();
    // the passive joints' torque in FD is zero along the whole horizon
    if (fd) {
      for (int j : model.unactuated_joints) EXPECT_EQ(ocp.torques().row(j).cwiseAbs().maxCoeff(), 0.0);
    }

    // exact products in dual numbers: dF along W equals the central difference of F
    ocp.enable_exact_products();
    const VecX<double> W = random_vector(rng, N * sd, 1.0);
    VecX<double> Fd(N * sd), dF(N * sd);
    ocp.residual_and_product(U, W, s.q0, s.v0, T, Fd, dF);
    EXPECT_LE((Fd - F).cwiseAbs().maxCoeff(), 1e-12 * F.cwiseAbs().maxCoeff());
    const double h = 1e-6;
    VecX<double> Fp(N * sd), Fm(N * sd);
    ocp.residual(VecX<double>(U + h * W), s.q0, s.v0, T, Fp);
    ocp.residual(VecX<double>(U - h * W), s.q0, s.v0, T, Fm);
    const VecX<double> difference = (Fp - Fm) / (2 * h);
    EXPECT_LE((dF - difference).cwiseAbs().maxCoeff() / difference.cwiseAbs().maxCoeff(), 1e-6);
  }
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const auto& [name, f, mode] = info.param;
  return name + "_" + to_string(f) + "_" + to_string(mode);
}

INSTANTIATE_TEST_SUITE_P(Models, UnderActuation,
                         ::testing::Combine(::testing::Values("acrobot", "pendubot", "cartpole", "passive_middle"),
                                            ::testing::Values(Formulation::kForwardDynamics,
                                                              Formulation::kInverseDynamics),
                                            ::testing::Values(DerivativeMode::kMatrix, DerivativeMode::kAdjoint)),
                         case_name);

TEST(UnderActuationModel, ImportMarksThePassiveJointsAndThePlantLeavesThemAlone) {
  const Problem p = passive_middle();
  EXPECT_EQ(p.model.actuated_joints, (std::vector<int>{0, 2}));
  EXPECT_EQ(p.model.unactuated_joints, std::vector<int>{1});
  // a variant rebuilt from its links keeps the actuation
  EXPECT_FALSE(p.model.link(1).actuated);
  EXPECT_TRUE(with_implicit_damping(p.model, 0.01).under_actuated());
}

TEST(UnderActuationModel, NothingToControlIsRefused) {
  const mj::ModelPtr m = mj::load_model_from_string(R"(<mujoco><worldbody><body><joint name="j" axis="0 1 0"/>
    <geom type="sphere" size="0.1" mass="1" pos="0 0 -1"/></body></worldbody>
    <actuator><motor joint="j"/></actuator></mujoco>)");
  std::vector<Link> links{mj::import_model(m.get(), "pendulum.xml").model.link(0)};
  links[0].actuated = false;
  const auto model = std::make_shared<const Model>(links, Vec3<double>(0, 0, -9.81), "pendulum.xml");
  const OcpWeights w{VecX<double>::Ones(1), VecX<double>::Ones(1), VecX<double>::Zero(1), VecX<double>::Ones(1)};
  EXPECT_NE(test::error_of([&] {
              OcpProblem(model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, w, VecX<double>::Zero(1), 5);
            }).find("no actuated joint"),
            std::string::npos);
}

}  // namespace
}  // namespace idmpc
