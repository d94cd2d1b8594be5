// Under-actuated models (formulations.md §Under-actuation): the residual of both formulations is
// the gradient of the discretized cost, as for the fully actuated ones, with
//   FD: the input the actuators' torques u (n_u), the joints' τ = Sᵀu (passive joints zero);
//   ID: the input the accelerations a (n) and, per passive joint, a multiplier ν of the stage's
//       equality constraint s_E u_E = 0 on its torque u_E = ID_E(q, v, a) − d̂_E,
// each with torque limits on the actuated joints (dummy d and multiplier ρ per bounded joint).
// The augmented cost J(U) is rolled out here with only RNEA/ABA from the library, and
// F = (1/Δτ) ∂J/∂U is checked by central differences in every derivative mode, with stages in
// lanes and one by one, and in dual numbers (exact products) against differences of F.
// The Riccati solver on the same problems: FD's converged inputs zero that F (Pontryagin's
// costates, independent of the solver's local models); ID's converged accelerations keep every
// passive torque at zero and their torques zero that F too (one problem, two formulations).
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
#include "idmpc/mujoco/reference.hpp"
#include "idmpc/solver/riccati.hpp"
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


// converged: one problem's optimum, whichever formulation the Riccati solver runs
class RiccatiUnderActuation : public ::testing::TestWithParam<std::string> {};

TEST_P(RiccatiUnderActuation, BothFormulationsConvergeToTheOptimumOfTheOneProblem) {
  const Problem p = problem_of(GetParam());
  const Model& model = p.model;
  const int n = model.n, N = 20;
  const double T = 0.6;
  std::mt19937 rng(5);
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2), VecX<double>::Zero(n),
                     random_vector(rng, n, 1e-2, 1e-1)};
  const VecX<double> q_ref = random_vector(rng, n, -0.5, 0.5), d_hat = random_vector(rng, n, -0.3, 0.3);
  const VecX<double> q0 = random_vector(rng, n, -0.5, 0.5), v0 = random_vector(rng, n, -0.5, 0.5);
  const MatX<double> L = MatX<double>::Random(2 * n, 2 * n);
  const MatX<double> P = L * L.transpose() + MatX<double>::Identity(2 * n, 2 * n);
  RiccatiSettings settings;
  settings.init_iterations = 300;
  settings.init_tolerance = 1e-10;
  for (const bool with_P : {false, true}) {
    SCOPED_TRACE(with_P ? "terminal P" : "diagonal terminal weights");
    std::vector<RiccatiSolver> solvers;
    for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      OcpProblem problem(model, f, DerivativeMode::kMatrix, w, q_ref, N);
      problem.set_disturbance(d_hat);
      if (with_P) problem.set_terminal_weight(P);
      solvers.emplace_back(std::move(problem), T, 1e-3, settings);
      EXPECT_LT(solvers.back().initialize(0.0, q0, v0), 1e-8) << to_string(f);
    }
    const RiccatiSolver& fd = solvers[0];
    const RiccatiSolver& id = solvers[1];
    ASSERT_EQ(fd.inputs().rows(), model.n_actuated());
    ASSERT_EQ(id.inputs().rows(), n);
    // C/GMRES's FD residual (no limits: the stage block is the input) at the actuated torques
    // of each solution: both are stationary points of the one problem (the nonconvex problem
    // may have several; from this start both formulations reach the same one without P)
    Shooting shooting(fd.problem());
    shooting.set_time(0.0);
    const auto fd_residual = [&](const MatX<double>& torques) {
      VecX<double> U(model.n_actuated() * N), F(model.n_actuated() * N);
      for (int i = 0; i < N; ++i) {
        for (int k = 0; k < model.n_actuated(); ++k) U[i * model.n_actuated() + k] = torques(model.actuated_joints[k], i);
      }
      shooting.residual(U, q0, v0, T, F);
      return F.norm();
    };
    EXPECT_LT(fd_residual(fd.torques()), 1e-6);
    EXPECT_LT(fd_residual(id.torques()), 1e-6);
    // ID: the passive torques vanish along the horizon
    for (int j : model.unactuated_joints) EXPECT_LT(id.torques().row(j).cwiseAbs().maxCoeff(), 1e-9);
    if (!with_P) {
      EXPECT_LT((id.torques() - fd.torques()).cwiseAbs().maxCoeff(), 1e-6 * (1 + fd.torques().cwiseAbs().maxCoeff()));
      EXPECT_LT((id.states() - fd.states()).cwiseAbs().maxCoeff(), 1e-7);
    }
    EXPECT_LT((id.first_input() - id.inputs().col(0)).norm(), 1e-15);
    for (int j : model.unactuated_joints) EXPECT_EQ(fd.first_input()[j], 0.0);
    EXPECT_EQ(fd.feedback_gain().rows(), model.n_actuated());
    EXPECT_EQ(id.feedback_gain().rows(), n);
  }
}

// ID's elimination of the passive rows is exact: one Riccati step from a rolled-out start is
// the solution of the stage QP written densely here (the local models' dynamics, Gauss–Newton
// cost and the linearized constraints τ_E + τ_E,x dx + τ_E,u du = 0, by its KKT system)
TEST_P(RiccatiUnderActuation, IdStepSolvesTheEqualityConstrainedQp) {
  const Problem p = problem_of(GetParam());
  const Model& model = p.model;
  const int n = model.n, N = 3, ne = n - model.n_actuated(), nx = 2 * n;
  const double T = 0.06, h = T / N;
  std::mt19937 rng(9);
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2), random_vector(rng, n, 1e-3, 1e-2),
                     random_vector(rng, n, 1e-2, 1e-1)};
  const VecX<double> q0 = random_vector(rng, n, -0.5, 0.5), v0 = random_vector(rng, n, -0.5, 0.5);
  OcpProblem problem(model, Formulation::kInverseDynamics, DerivativeMode::kMatrix, w, random_vector(rng, n, -0.5, 0.5), N);
  RiccatiSettings settings;
  settings.init_iterations = 0;  // the start is the rollout of zero accelerations
  RiccatiSolver solver(problem, T, 1e-3, settings);
  solver.initialize(0.0, q0, v0);
  const MatX<double> X = solver.states(), U = solver.inputs();
  ASSERT_GT(solver.torques().row(model.unactuated_joints[0]).cwiseAbs().maxCoeff(), 1e-3) << "a start off the constraint";
  solver.iterate(0.0, q0, v0, false);
  const MatX<double> dU = solver.inputs() - U, dX = solver.states() - X;

  // unknowns z = (du_0, dx_1, du_1, …, dx_N), dx_0 = 0; equalities: dynamics, then constraints
  const int nz = N * n + N * nx, neq = N * nx + N * ne;
  MatX<double> H = MatX<double>::Zero(nz, nz), G = MatX<double>::Zero(neq, nz);
  VecX<double> g = VecX<double>::Zero(nz), r = VecX<double>::Zero(neq);
  const auto u_at = [&](int i) { return i * (n + nx); };
  const auto x_at = [&](int i) { return i * (n + nx) - nx; };  // stage i ≥ 1
  auto lm = solver.problem().make_local_model();
  solver.problem().set_stage_times(0.0, h);
  for (int i = 0; i < N; ++i) {
    StageLocal st(n);
    lm->local_model(solver.problem().terms(), i, h, X.col(i), U.col(i), st);
    H.block(u_at(i), u_at(i), n, n) = st.L_uu;
    g.segment(u_at(i), n) = st.l_u;
    if (i > 0) {
      H.block(x_at(i), x_at(i), nx, nx) = st.L_xx;
      H.block(u_at(i), x_at(i), n, nx) = st.L_ux;
      H.block(x_at(i), u_at(i), nx, n) = st.L_ux.transpose();
      g.segment(x_at(i), nx) = st.l_x;
      G.block(i * nx, x_at(i), nx, nx) = st.A;
    }
    // A dx_i + B du_i − dx_{i+1} = −b_i
    G.block(i * nx, u_at(i), nx, n) = st.B;
    G.block(i * nx, x_at(i + 1), nx, nx) = -MatX<double>::Identity(nx, nx);
    r.segment(i * nx, nx) = -(st.x_next - X.col(i + 1));
    for (int k = 0; k < ne; ++k) {
      const int j = model.unactuated_joints[static_cast<size_t>(k)];
      G.block(N * nx + i * ne + k, u_at(i), 1, n) = st.tau_u.row(j);
      if (i > 0) G.block(N * nx + i * ne + k, x_at(i), 1, nx) = st.tau_x.row(j);
      r[N * nx + i * ne + k] = -st.tau[j];
    }
  }
  TerminalLocal term(n);
  lm->terminal(solver.problem().terms(), N, X.col(N), term);
  H.block(x_at(N), x_at(N), nx, nx) += term.L_xx;
  g.segment(x_at(N), nx) += term.l_x;
  MatX<double> K = MatX<double>::Zero(nz + neq, nz + neq);
  K << H, G.transpose(), G, MatX<double>::Zero(neq, neq);
  VecX<double> rhs(nz + neq);
  rhs << -g, r;
  const VecX<double> z = K.fullPivLu().solve(rhs);
  // (the recursion's Q_uu carries a regularization of 1e-9 of its diagonal)
  for (int i = 0; i < N; ++i) {
    EXPECT_LT((dU.col(i) - z.segment(u_at(i), n)).norm(), 1e-7 * (1 + dU.norm())) << "stage " << i;
    EXPECT_LT((dX.col(i + 1) - z.segment(x_at(i + 1), nx)).norm(), 1e-7 * (1 + dX.norm())) << "stage " << i + 1;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, RiccatiUnderActuation,
                         ::testing::Values("acrobot", "pendubot", "cartpole", "passive_middle"));

// ID's passive-torque rows at the input's block (OcpProblem::scale_passive_rows): s_E = mean over
// the passive joints of C_E/M_EE, C the input block's diagonal (MᵀRM)_jj + Q_a,j + c_j with
// c = Δτ(Q_q T_f³/3 + Q_v T_f), here recomputed from MuJoCo's mass matrix at q_ref; FD has no such
// rows. The constraint is the same: its rows of F are s_E·u_E of the stage torques.
TEST(UnderActuationModel, PassiveTorqueRowsAreScaledAtTheInputsBlock) {
  for (const char* name : {"cartpole", "pendubot", "acrobot"}) {
    SCOPED_TRACE(name);
    const Problem p = load_problem(std::string(IDMPC_SOURCE_DIR "/mjcf/") + name + ".xml");
    const Model& model = p.model;
    const int n = model.n, N = 10;
    const double Tf = 0.6, dtau = Tf / N;
    const OcpWeights w{VecX<double>::LinSpaced(n, 3.0, 10.0), VecX<double>::Constant(n, 0.1),
                       VecX<double>::Constant(n, 1e-3), VecX<double>::LinSpaced(n, 1e-3, 4e-3)};
    const VecX<double> q_ref = VecX<double>::LinSpaced(n, 0.1, -0.2);
    Shooting ocp(model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, w, q_ref, N);
    OcpProblem& problem = ocp.problem();
    double mean_R = 0;
    for (int j : model.actuated_joints) mean_R += w.R[j] / model.n_actuated();
    EXPECT_DOUBLE_EQ(problem.terms().passive_scale(), mean_R);
    problem.scale_passive_rows(Tf);
    mj::Reference ref(p.m.get());
    const MatX<double> M = ref.mass_matrix(q_ref);
    double expected = 0;
    for (int j : model.unactuated_joints) {
      double C = w.Qa[j] + dtau * (w.Qq[j] * Tf * Tf * Tf / 3 + w.Qv[j] * Tf);
      for (int k = 0; k < n; ++k) C += M(k, j) * M(k, j) * w.R[k];
      expected += C / M(j, j) / static_cast<double>(model.unactuated_joints.size());
    }
    EXPECT_NEAR(problem.terms().passive_scale(), expected, 1e-10 * expected);
    EXPECT_GT(std::abs(expected / mean_R - 1), 0.3) << "the case must move s_E";
    // the ν rows of F: s_E times the passive joints' torques
    const int sd = problem.stage_dim(), ne = problem.equality_dim();
    std::mt19937 rng(5);
    const VecX<double> U = random_vector(rng, N * sd, 1.0);
    VecX<double> F(N * sd);
    ocp.residual(U, VecX<double>::Zero(n), VecX<double>::Zero(n), Tf, F);
    for (int i = 0; i < N; ++i) {
      for (int k = 0; k < ne; ++k) {
        const int j = model.unactuated_joints[static_cast<std::size_t>(k)];
        const double F_nu = F[i * sd + sd - ne + k];
        EXPECT_NEAR(F_nu, expected * ocp.torques()(j, i), 1e-9 * std::max(1.0, std::abs(F_nu)));
      }
    }
    // FD: nothing to scale
    OcpProblem fd(model, Formulation::kForwardDynamics, DerivativeMode::kAdjoint, w, q_ref, N);
    const double before = fd.terms().passive_scale();
    fd.scale_passive_rows(Tf);
    EXPECT_EQ(fd.terms().passive_scale(), before);
  }
}

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
