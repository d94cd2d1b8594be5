// The stage local models (ocp/local_model.hpp) against central differences of the stage
// written here from the dynamics kernels alone: the Euler step x⁺ = (q + Δτv, v + Δτa) with FD's
// a = ABA(q, v, u + d̂) or ID's a = u, the torque τ = u (FD) or RNEA(q, v, u) − d̂ (ID), and the
// cost Δτ·(StageTerms::stage_cost(q, v, τ) + ½uᵀQ_a u (ID)) — on models with armature, damping
// made implicit, stiffness, smooth friction, a disturbance estimate, a frame target and a joint
// reference that moves.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <tuple>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/ocp/problem.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::Problem;
using test::random_vector;

constexpr double kDtau = 0.02;
constexpr int kN = 6;

// the stage as the test writes it
struct Reference {
  const OcpProblem& problem;
  mutable Data data;
  explicit Reference(const OcpProblem& p) : problem(p), data(p.model()) {}
  int n() const { return problem.n(); }
  bool fd() const { return problem.formulation() == Formulation::kForwardDynamics; }
  VecX<double> torque(const VecX<double>& x, const VecX<double>& u) const {
    const int n = this->n();
    if (fd()) return u;
    return rnea(problem.model(), data, VecX<double>(x.head(n)), VecX<double>(x.tail(n)), u) -
           problem.disturbance();
  }
  VecX<double> next(const VecX<double>& x, const VecX<double>& u) const {
    const int n = this->n();
    const VecX<double> q = x.head(n), v = x.tail(n);
    const VecX<double> a = fd() ? VecX<double>(aba(problem.model(), data, q, v, VecX<double>(u + problem.disturbance())))
                                : u;
    VecX<double> out(2 * n);
    out << q + kDtau * v, v + kDtau * a;
    return out;
  }
  double cost(int i, const VecX<double>& x, const VecX<double>& u) const {
    const int n = this->n();
    const VecX<double> tau = torque(x, u);
    double c = problem.stage_cost(i, x.head(n), x.tail(n), tau);
    if (!fd()) c += 0.5 * u.dot(problem.weights().Qa.cwiseProduct(u));
    return kDtau * c;
  }
};

// central differences of a vector function of z ∈ {x, u}: columns ∂f/∂z_j
template <typename F> MatX<double> jacobian(F f, const VecX<double>& z, double h = 1e-6) {
  const VecX<double> f0 = f(z);
  MatX<double> J(f0.size(), z.size());
  for (Eigen::Index j = 0; j < z.size(); ++j) {
    VecX<double> zp = z, zm = z;
    zp[j] += h;
    zm[j] -= h;
    J.col(j) = (f(zp) - f(zm)) / (2 * h);
  }
  return J;
}

double relative(const MatX<double>& a, const MatX<double>& b) { return (a - b).norm() / (1 + b.norm()); }

// a model with every term the horizon models: the file's armature, damping and stiffness,
// smooth friction, and (implicit) its damping over the horizon step
Model full_model(const Problem& p, std::mt19937& rng) {
  const int n = p.model.n;
  Model m = with_joint_friction(p.model, random_vector(rng, n, 0.1, 0.5), random_vector(rng, n, 0.2, 0.5));
  return with_implicit_damping(m, kDtau);
}

OcpProblem make_problem(const Model& model, Formulation f, std::mt19937& rng, const VecX<double>& q_ref) {
  const int n = model.n;
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                     f == Formulation::kInverseDynamics ? random_vector(rng, n, 1e-3, 1e-2) : VecX<double>::Zero(n),
                     random_vector(rng, n, 1e-3, 1e-2)};
  OcpProblem problem(model, f, DerivativeMode::kMatrix, w, q_ref, kN);
  FrameTarget target;
  target.frame = Frame{"tip", n - 1, Transform<double>{}};
  target.frame.placement.r = Vec3<double>(0.05, 0.02, 0.1);
  target.position_weight = random_vector(rng, 3, 20.0, 80.0);
  target.orientation_weight = 3.0;
  FrameKinematics<double> fk(model, target.frame);
  fk.compute(model, q_ref);
  target.position = fk.position();
  target.rotation = fk.rotation();
  problem.set_frame_target(target);
  return problem;
}

using Param = std::tuple<std::string, Formulation>;
class LocalModelTest : public ::testing::TestWithParam<Param> {};

TEST_P(LocalModelTest, JacobiansAndGradientsAreThoseOfTheStage) {
  const auto& [file, formulation] = GetParam();
  const Problem p = load_problem(std::string(IDMPC_SOURCE_DIR "/mjcf/") + file);
  std::mt19937 rng(7);
  const Model model = full_model(p, rng);
  const int n = model.n;
  OcpProblem problem = make_problem(model, formulation, rng, random_vector(rng, n, 0.8));
  problem.set_disturbance(random_vector(rng, n, 0.3));
  // a joint target that moves: stage i sees its own q_ref, v_ref and u_ref
  MatX<double> waypoints(n, 3);
  for (int k = 0; k < 3; ++k) waypoints.col(k) = random_vector(rng, n, 0.8);
  problem.set_joint_trajectory(std::make_shared<WaypointTrajectory>(std::vector<double>{0.0, 0.3, 0.6}, waypoints));
  problem.set_stage_times(0.3, kDtau);
  const Reference ref(problem);
  auto lm = problem.make_local_model();
  StageLocal st(n);
  for (int i : {0, 3}) {
    const VecX<double> x = random_vector(rng, 2 * n, 0.7);
    const VecX<double> u = formulation == Formulation::kForwardDynamics ? random_vector(rng, n, 4.0)
                                                                        : random_vector(rng, n, 2.0);
    lm->local_model(problem.terms(), i, kDtau, x, u, st);
    EXPECT_LE(relative(st.x_next, ref.next(x, u)), 1e-14);
    EXPECT_LE(relative(st.tau, ref.torque(x, u)), 1e-12);
    EXPECT_NEAR(st.cost, ref.cost(i, x, u), 1e-12 * (1 + std::abs(st.cost)));
    const auto fx = [&](const VecX<double>& z) { return ref.next(z, u); };
    const auto fu = [&](const VecX<double>& z) { return ref.next(x, z); };
    EXPECT_LE(relative(st.A, jacobian(fx, x)), 1e-7) << "A, stage " << i;
    EXPECT_LE(relative(st.B, jacobian(fu, u)), 1e-7) << "B, stage " << i;
    const auto tx = [&](const VecX<double>& z) { return ref.torque(z, u); };
    const auto tu = [&](const VecX<double>& z) { return ref.torque(x, z); };
    EXPECT_LE(relative(st.tau_x, jacobian(tx, x)), 1e-7) << "tau_x, stage " << i;
    EXPECT_LE(relative(st.tau_u, jacobian(tu, u)), 1e-7) << "tau_u, stage " << i;
    const auto cx = [&](const VecX<double>& z) { return VecX<double>::Constant(1, ref.cost(i, z, u)); };
    const auto cu = [&](const VecX<double>& z) { return VecX<double>::Constant(1, ref.cost(i, x, z)); };
    EXPECT_LE(relative(st.l_x.transpose(), jacobian(cx, x)), 1e-7) << "l_x, stage " << i;
    EXPECT_LE(relative(st.l_u.transpose(), jacobian(cu, u)), 1e-7) << "l_u, stage " << i;
    // the terminal cost: φ(x_N) at stage N's references
    TerminalLocal term(n);
    lm->terminal(problem.terms(), kN, x, term);
    const auto phi = [&](const VecX<double>& z) {
      return VecX<double>::Constant(1, problem.stage_cost(kN, z.head(n), z.tail(n), problem.terms().u_ref(kN)));
    };
    EXPECT_NEAR(term.cost, phi(x)[0], 1e-12 * (1 + term.cost));
    EXPECT_LE(relative(term.l_x.transpose(), jacobian(phi, x)), 1e-7);
  }
}

// Where every residual of the cost vanishes (at the target, at rest, holding torque, the frame on
// its pose) the Gauss–Newton Hessian is the exact one: second differences of the stage's cost
TEST_P(LocalModelTest, GaussNewtonHessianIsExactWhereTheResidualsVanish) {
  const auto& [file, formulation] = GetParam();
  const Problem p = load_problem(std::string(IDMPC_SOURCE_DIR "/mjcf/") + file);
  std::mt19937 rng(11);
  const Model model = full_model(p, rng);
  const int n = model.n;
  const VecX<double> q_ref = random_vector(rng, n, 0.8);
  OcpProblem problem = make_problem(model, formulation, rng, q_ref);
  problem.set_disturbance(random_vector(rng, n, 0.3));
  const Reference ref(problem);
  VecX<double> x(2 * n);
  x << q_ref, VecX<double>::Zero(n);
  const VecX<double> u = formulation == Formulation::kForwardDynamics ? VecX<double>(problem.terms().u_ref(1))
                                                                      : VecX<double>::Zero(n);
  auto lm = problem.make_local_model();
  StageLocal st(n);
  lm->local_model(problem.terms(), 1, kDtau, x, u, st);
  EXPECT_NEAR(st.cost, 0.0, 1e-12);
  VecX<double> z(3 * n);
  z << x, u;
  const double h = 1e-4;
  MatX<double> H(3 * n, 3 * n);
  auto c = [&](VecX<double> w) { return ref.cost(1, w.head(2 * n), w.tail(n)); };
  for (int j = 0; j < 3 * n; ++j) {
    for (int k = 0; k < 3 * n; ++k) {
      VecX<double> pp = z, pm = z, mp = z, mm = z;
      pp[j] += h, pp[k] += h, pm[j] += h, pm[k] -= h, mp[j] -= h, mp[k] += h, mm[j] -= h, mm[k] -= h;
      H(j, k) = (c(pp) - c(pm) - c(mp) + c(mm)) / (4 * h * h);
    }
  }
  MatX<double> G(3 * n, 3 * n);
  G << st.L_xx, st.L_ux.transpose(), st.L_ux, st.L_uu;
  EXPECT_LE(relative(G, H), 1e-5) << "local model\n" << G << "\nsecond differences\n" << H;
}

// add_torque_terms adds τ'ᵀdiag(W)τ' and τ'ᵀg for any weight and gradient (a constraint's barrier)
TEST_P(LocalModelTest, TorqueTermsAreTheProductsWithTheTorqueJacobian) {
  const auto& [file, formulation] = GetParam();
  const Problem p = load_problem(std::string(IDMPC_SOURCE_DIR "/mjcf/") + file);
  std::mt19937 rng(13);
  const Model model = full_model(p, rng);
  const int n = model.n;
  OcpProblem problem = make_problem(model, formulation, rng, random_vector(rng, n, 0.8));
  auto lm = problem.make_local_model();
  StageLocal st(n);
  const VecX<double> x = random_vector(rng, 2 * n, 0.7), u = random_vector(rng, n, 2.0);
  lm->linearize(problem.terms(), 2, kDtau, x, u, st);
  const StageLocal before = st;
  const VecX<double> W = random_vector(rng, n, 0.1, 3.0), g = random_vector(rng, n, 1.0);
  lm->add_torque_terms(W, g, st);
  MatX<double> T(n, 3 * n);
  T << before.tau_x, before.tau_u;
  const MatX<double> H = T.transpose() * W.asDiagonal() * T;
  const VecX<double> gz = T.transpose() * g;
  EXPECT_LE(relative(st.L_xx - before.L_xx, H.topLeftCorner(2 * n, 2 * n)), 1e-13);
  EXPECT_LE(relative(st.L_ux - before.L_ux, H.bottomLeftCorner(n, 2 * n)), 1e-13);
  EXPECT_LE(relative(st.L_uu - before.L_uu, H.bottomRightCorner(n, n)), 1e-13);
  EXPECT_LE(relative(st.l_x - before.l_x, gz.head(2 * n)), 1e-13);
  EXPECT_LE(relative(st.l_u - before.l_u, gz.tail(n)), 1e-13);
}

INSTANTIATE_TEST_SUITE_P(Models, LocalModelTest,
                         ::testing::Combine(::testing::Values("arm4.xml", "panda.xml", "tree.xml"),
                                            ::testing::Values(Formulation::kForwardDynamics,
                                                              Formulation::kInverseDynamics)),
                         [](const ::testing::TestParamInfo<Param>& info) {
                           std::string name = std::get<0>(info.param);
                           name = name.substr(0, name.find('.'));
                           return name + (std::get<1>(info.param) == Formulation::kForwardDynamics ? "_fd" : "_id");
                         });

}  // namespace
}  // namespace idmpc
