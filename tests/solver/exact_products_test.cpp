// Exact directional products (formulations.md §Exact products): Shooting::residual_and_product evaluates the residual
// in dual numbers, so that its tangent part is F'(U)·W. Checked against the residual itself
// (the values), against central differences (error O(h²): it shrinks 4× when h halves) and
// forward differences (O(h): 2×), on random points of every shipped model, for both
// formulations, both derivative modes, stages in lanes or not, with torque limits, a
// disturbance estimate, a frame target and multiple shooting's defects. Then the dual kernels
// against the analytic derivatives, and C/GMRES with exact products in the closed loop.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/controller.hpp"
#include "idmpc/solver/shooting.hpp"
#include "idmpc/spatial/dual.hpp"
#include "support/problems.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

using test::random_vector;

constexpr int kN = 6;
constexpr double kT = 0.3;

struct Variant {
  Formulation formulation;
  DerivativeMode mode;
  bool lanes;
};

std::string label(const Variant& s) {
  return to_string(s.formulation) + "/" + to_string(s.mode) + (s.lanes ? "/lanes" : "/stages");
}

const std::vector<Variant>& setups() {
  static const std::vector<Variant> out = [] {
    std::vector<Variant> v;
    for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      for (DerivativeMode m : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
        for (bool lanes : {false, true}) v.push_back({f, m, lanes});
      }
    }
    return v;
  }();
  return out;
}

// the problem of one model: the paper's weights with Q_a, torque limits on every other joint,
// a disturbance estimate and a frame target on the last link
Shooting make_problem(const Model& model, const Variant& s, std::mt19937& rng) {
  const int n = model.n;
  TorqueLimits limits{VecX<double>::Constant(n, -INFINITY), VecX<double>::Constant(n, INFINITY)};
  for (int j = 0; j < n; j += 2) {
    limits.lower[j] = -30;
    limits.upper[j] = 20;
  }
  OcpProblem problem(model, s.formulation, s.mode, test::paper_weights(n, 1e-3), random_vector(rng, n, 1.0), kN,
                     limits);
  problem.set_disturbance(random_vector(rng, n, 0.5));
  FrameTarget target;
  target.frame = Frame{"tip", n - 1, Transform<double>{Mat3<double>::Identity(), Vec3<double>(0.05, 0.0, 0.1)}};
  target.position_weight = Vec3<double>(40, 50, 60);
  target.orientation_weight = 3;
  target.position = Vec3<double>(0.2, -0.1, 0.3);
  target.rotation = Eigen::AngleAxisd(0.7, Vec3<double>(1, 2, 3).normalized()).toRotationMatrix();
  problem.set_frame_target(target);
  problem.set_stages_in_lanes(s.lanes);
  Shooting ocp(std::move(problem));
  ocp.enable_exact_products();
  return ocp;
}

// a random point: inputs of the size of the formulation's, d and ρ positive, ν (the passive
// torques' multipliers of an under-actuated ID problem) any
VecX<double> random_point(const Shooting& ocp, std::mt19937& rng) {
  const int ni = ocp.problem().input_dim(), m = ocp.problem().m(), ne = ocp.problem().equality_dim();
  const int sd = ocp.stage_dim();
  // FD's torques of the size of ID's accelerations: larger ones swing a tree's light links so
  // fast that the rollout leaves the differences' asymptotic regime
  const double scale = 2.0;
  VecX<double> U(ocp.dim());
  for (int i = 0; i < ocp.N(); ++i) {
    U.segment(i * sd, ni) = random_vector(rng, ni, scale);
    U.segment(i * sd + ni, 2 * m) = random_vector(rng, 2 * m, 0.5, 2.0);
    U.segment(i * sd + ni + 2 * m, ne) = random_vector(rng, ne, scale);
  }
  return U;
}

struct NamedModel {
  std::string name;
  Model model;
};

const std::vector<NamedModel>& models() {
  static const std::vector<NamedModel> out = [] {
    std::vector<NamedModel> v;
    // the under-actuated models last
    for (const bool under_actuated : {false, true}) {
      for (const std::string& path : test::shipped_model_paths()) {
        Model model = test::load_problem(path).model;
        if (model.under_actuated() == under_actuated) {
          v.push_back({std::filesystem::path(path).stem().string(), std::move(model)});
        }
      }
    }
    return v;
  }();
  return out;
}

class ExactProducts : public ::testing::TestWithParam<int> {};

TEST_P(ExactProducts, ValuesAreTheResidualAndTangentsConvergeAsDifferencesDo) {
  const NamedModel& M = models()[static_cast<size_t>(GetParam())];
  for (const Variant& s : setups()) {
    SCOPED_TRACE(M.name + " " + label(s));
    std::seed_seq seed(M.name.begin(), M.name.end());  // each model's own, whatever the others
    std::mt19937 rng(seed);
    Shooting ocp = make_problem(M.model, s, rng);
    const int n = ocp.n(), dim = ocp.dim();
    const VecX<double> U = random_point(ocp, rng), W = random_vector(rng, dim, 1.0);
    const VecX<double> q0 = random_vector(rng, n, 1.0), v0 = random_vector(rng, n, 1.0);
    ocp.set_time(0.1);

    VecX<double> F(dim), Fd(dim), dF(dim), Fp(dim), Fm(dim);
    ocp.residual(U, q0, v0, kT, F);
    ocp.residual_and_product(U, W, q0, v0, kT, Fd, dF);
    // the values are the residual: the same stage arithmetic, in lanes or not
    EXPECT_LE((Fd - F).norm(), 1e-10 * (1 + F.norm()));
    ASSERT_TRUE(dF.allFinite());
    ASSERT_GT(dF.norm(), 0);

    // central and forward differences against the exact product at h and h/2
    auto central = [&](double h) {
      ocp.residual(U + h * W, q0, v0, kT, Fp);
      ocp.residual(U - h * W, q0, v0, kT, Fm);
      return ((Fp - Fm) / (2 * h) - dF).norm();
    };
    auto forward = [&](double h) {
      ocp.residual(U + h * W, q0, v0, kT, Fp);
      return ((Fp - F) / h - dF).norm();
    };
    // a step in the differences' asymptotic regime: halved from 5e-2 until the central
    // difference's error is a small part of the product (a stiff rollout, e.g. FD's torques on a
    // tree's light links, is far from it at 5e-2)
    double h = 5e-2;
    for (int k = 0; k < 10 && central(h) > 0.05 * dF.norm(); ++k) h /= 2;
    const double c1 = central(h), c2 = central(h / 2), f1 = forward(h), f2 = forward(h / 2);
    EXPECT_NEAR(c1 / c2, 4.0, 0.6) << "central: " << c1 << " at h, " << c2 << " at h/2, |dF| " << dF.norm();
    EXPECT_NEAR(f1 / f2, 2.0, 0.3) << "forward: " << f1 << " at h, " << f2 << " at h/2, |dF| " << dF.norm();
    // and close at a small step, up to the evaluations' own rounding noise over 2h (measured by
    // the two evaluations of F above; it is large for FD's dense M⁻¹ on long chains)
    const double noise = (Fd - F).norm(), small = 1e-5;
    EXPECT_LE(central(small), 1e-6 * dF.norm() + 10 * noise / small);
  }
}

INSTANTIATE_TEST_SUITE_P(Shipped, ExactProducts, ::testing::Range(0, static_cast<int>(models().size())),
                         [](const ::testing::TestParamInfo<int>& info) {
                           std::string s = models()[static_cast<size_t>(info.param)].name;
                           for (char& c : s) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return s;
                         });

// the condensed residual of multiple shooting (given defects) has exact products too
TEST(ExactProductsDefects, TangentOfTheCondensedResidual) {
  const Model& model = models().front().model;
  for (const Variant& s : setups()) {
    SCOPED_TRACE(label(s));
    std::mt19937 rng(3);
    Shooting ocp = make_problem(model, s, rng);
    const int n = ocp.n(), dim = ocp.dim();
    ShootingDefects e;
    e.resize(n, kN);
    for (MatX<double>* x : {&e.q, &e.v, &e.lmd, &e.gmm}) x->setRandom() *= 0.01;
    const VecX<double> U = random_point(ocp, rng), W = random_vector(rng, dim, 1.0);
    const VecX<double> q0 = random_vector(rng, n, 1.0), v0 = random_vector(rng, n, 1.0);
    VecX<double> F(dim), Fd(dim), dF(dim), Fp(dim), Fm(dim);
    ocp.residual(U, q0, v0, kT, F, &e);
    ocp.residual_and_product(U, W, q0, v0, kT, Fd, dF, &e);
    EXPECT_LE((Fd - F).norm(), 1e-10 * (1 + F.norm()));
    const ShootingTrajectory tangent = ocp.trajectory_tangent();
    const double h = 1e-5;
    ocp.residual(U + h * W, q0, v0, kT, Fp, &e);
    const ShootingTrajectory plus = ocp.trajectory();
    ocp.residual(U - h * W, q0, v0, kT, Fm, &e);
    const ShootingTrajectory& minus = ocp.trajectory();
    EXPECT_LE(((Fp - Fm) / (2 * h) - dF).norm(), 1e-6 * dF.norm());
    // the trajectories' tangents (multiple shooting moves its stored trajectories along them);
    // λ_0, γ_0 are never computed
    auto near = [&](const MatX<double>& t, const MatX<double>& p, const MatX<double>& m, int from) {
      const MatX<double> cd = (p - m).rightCols(p.cols() - from) / (2 * h);
      EXPECT_LE((t.rightCols(t.cols() - from) - cd).norm(), 1e-6 * (1 + cd.norm()));
    };
    near(tangent.q, plus.q, minus.q, 0);
    near(tangent.v, plus.v, minus.v, 0);
    near(tangent.lmd, plus.lmd, minus.lmd, 1);
    near(tangent.gmm, plus.gmm, minus.gmm, 1);
  }
}

TEST(ExactProductsUse, WithoutEnablingThrows) {
  const Model& model = models().front().model;
  Shooting ocp(model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, test::paper_weights(model.n, 1e-3),
               VecX<double>::Zero(model.n), 4);
  VecX<double> U = VecX<double>::Zero(ocp.dim()), F(ocp.dim()), dF(ocp.dim());
  const VecX<double> x = VecX<double>::Zero(model.n);
  EXPECT_THROW(ocp.residual_and_product(U, U, x, x, 0.1, F, dF), std::logic_error);
}

// the dual kernels against the analytic derivatives (themselves checked against MuJoCo and
// finite differences in dynamics_test): the tangent of RNEA along (δq, δv, δa) is
// ∂τ/∂q δq + ∂τ/∂v δv + M δa, that of ABA along (δq, δv, δτ) is ∂q̈/∂q δq + ∂q̈/∂v δv + M⁻¹ δτ
TEST(DualKernels, TangentsAreTheAnalyticDerivatives) {
  // the shipped models, and the first (arm4) with friction loss f·tanh(v/ε) on every joint (the real arms'
  // horizon model): its tangent goes through Dual's tanh. ε = 0.5 rad/s puts the random
  // velocities (|v| ≤ 1) on the curved part of tanh, where a wrong slope shows.
  std::vector<NamedModel> cases = models();
  const NamedModel& first = models().front();
  cases.push_back({first.name + "_friction", with_joint_friction(first.model, VecX<double>::Constant(first.model.n, 0.8),
                                                                 VecX<double>::Constant(first.model.n, 0.5))});
  for (const NamedModel& M : cases) {
    SCOPED_TRACE(M.name);
    const Model& model = M.model;
    const int n = model.n;
    std::mt19937 rng(11);
    const VecX<double> q = random_vector(rng, n, 1.0), v = random_vector(rng, n, 1.0),
                       a = random_vector(rng, n, 1.0), tau = random_vector(rng, n, 5.0);
    const VecX<double> dq = random_vector(rng, n, 1.0), dv = random_vector(rng, n, 1.0),
                       da = random_vector(rng, n, 1.0);
    Data data(model, DataParts::rnea() | DataParts::rnea_derivatives() | DataParts::aba() |
                         DataParts::aba_derivatives() | DataParts::minv_matrix());
    DataTpl<Dual> dual(model, DataParts::rnea() | DataParts::aba());

    rnea_derivatives(model, data, q, v, a);
    const VecX<double> dtau = data.dtau_dq * dq + data.dtau_dv * dv + data.M * da;
    const VecX<Dual> tau_d = rnea(model, dual, seeded(q, dq), seeded(v, dv), seeded(a, da));
    for (int j = 0; j < n; ++j) {
      EXPECT_NEAR(tau_d[j].x, data.tau[j], 1e-12 * (1 + std::abs(data.tau[j])));
      EXPECT_NEAR(tau_d[j].dx, dtau[j], 1e-10 * (1 + dtau.cwiseAbs().maxCoeff())) << "joint " << j;
    }

    aba_derivatives(model, data, q, v, tau);
    const VecX<double> dqdd = data.da_dq * dq + data.da_dv * dv + data.Minv * da;
    const VecX<Dual> qdd_d = aba(model, dual, seeded(q, dq), seeded(v, dv), seeded(tau, da));
    for (int j = 0; j < n; ++j) {
      EXPECT_NEAR(qdd_d[j].dx, dqdd[j], 1e-9 * (1 + dqdd.cwiseAbs().maxCoeff())) << "joint " << j;
    }
  }
}

// C/GMRES with exact products in the closed loop of the paper's swing-up (the controller's
// model as the plant, explicit Euler at Δt), FD and ID: the loop runs, and the residual it
// tracks is at least as small as with differences (the mean over t ≥ 0.1 s)
TEST(ExactProductsCgmres, TracksTheResidualInBothFormulations) {
  const auto model = std::make_shared<const Model>(models().front().model);  // arm4
  const int n = model->n;
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    double mean[2] = {0, 0};
    for (Products p : {Products::kDifference, Products::kExact}) {
      SCOPED_TRACE(to_string(f) + " " + to_string(p));
      ControllerSettings settings;
      settings.formulation = f;
      settings.weights = test::paper_weights(n, 1e-4);
      settings.q_ref = VecX<double>::Zero(n);
      settings.cgmres.products = p;
      Controller controller(model, settings);
      VecX<double> q = VecX<double>::Zero(n), v = VecX<double>::Zero(n);
      q[0] = -M_PI;  // hanging
      Data data(*model, DataParts::rnea() | DataParts::aba());
      VecX<double> tau = controller.initialize(q, v);
      const double dt = settings.cgmres.dt;
      int counted = 0;
      for (int k = 0; k < 300; ++k) {
        const double t = k * dt;
        ASSERT_TRUE(controller.update(t, q, v)) << controller.failure();
        if (t >= 0.1) {
          mean[p == Products::kExact ? 1 : 0] += controller.solver().residual_norm();
          ++counted;
        }
        const VecX<double> a = aba(*model, data, q, v, tau);
        q += dt * v;
        v += dt * a;
        tau = controller.torque();
      }
      mean[p == Products::kExact ? 1 : 0] /= counted;
    }
    std::printf("%s: mean |F| over t >= 0.1 s: difference %.3g, exact %.3g\n", to_string(f).c_str(), mean[0],
                mean[1]);
    EXPECT_LE(mean[1], 1.01 * mean[0]);
  }
}

}  // namespace
}  // namespace idmpc
