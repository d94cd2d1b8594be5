// The residual is the gradient of the discretized cost (formulations.md §Rollout, costates and residual): with
//   J(U) = Σ_i Δτ L(q_i, v_i, a_i, u_i) + φ(q_N, v_N)
// along the explicit-Euler rollout, the costate recursions are the discrete adjoint, so
//   F_i = (1/Δτ) ∂J/∂U_i
// for both formulations (U = torques for FD, accelerations for ID) and both derivative modes.
// The cost is rolled out here independently, with only RNEA/ABA from the library.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "idmpc/solver/shooting.hpp"
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

// the bounded joints' data of the augmented cost, computed here from the limits and R (the
// constraint scale s = R/Δ of torque_limits.hpp); r_d is a parameter of the problem: taken from it
struct Bounds {
  std::vector<int> joint;
  VecX<double> middle, half_range, scale, r_d;
  int m() const { return static_cast<int>(joint.size()); }
};

Bounds bounds_of(const TorqueLimits& limits, const VecX<double>& R, const VecX<double>& r_d) {
  Bounds b;
  for (Eigen::Index j = 0; j < limits.lower.size(); ++j) {
    if (std::isfinite(limits.lower[j])) b.joint.push_back(static_cast<int>(j));
  }
  const int m = b.m();
  b.middle.resize(m);
  b.half_range.resize(m);
  b.scale.resize(m);
  for (int k = 0; k < m; ++k) {
    const int j = b.joint[static_cast<size_t>(k)];
    b.middle[k] = 0.5 * (limits.upper[j] + limits.lower[j]);
    b.half_range[k] = 0.5 * (limits.upper[j] - limits.lower[j]);
    b.scale[k] = R[j] / (limits.upper[j] - limits.lower[j]);
  }
  b.r_d = r_d;
  return b;
}

// J(U) of formulations.md §Costs and §Torque limits: FD rolls out a_i = FD(q_i, v_i, u_i), ID computes
// u_i = ID(q_i, v_i, a_i); the torque cost is ½(u − u_ref)ᵀR(u − u_ref). With torque limits each
// stage block of U is (input, d, ρ) and the stage adds the Lagrangian's ρᵀ(s∘c) − r_dᵀd, with
// c_k = (u_j − ū_k)² + d_k² − (Δ_k/2)² for the bounded joints j = joint[k]. With a disturbance
// estimate d̂ (formulations.md §Disturbance observer; empty: none) the model's joint torque is u + d̂: FD rolls out
// a_i = FD(q_i, v_i, u_i + d̂), ID computes u_i = ID(q_i, v_i, a_i) − d̂ (u_ref is the caller's).
//
// With `moving` (the references of a moving target and a frame cost), stage i (N: the terminal
// cost) sees its own q_ref, v_ref and u_ref, and adds `moving->frame(i, q_i)`.
struct StageReferences {
  std::function<void(int i, VecX<double>& q_ref, VecX<double>& v_ref, VecX<double>& u_ref)> joint;
  std::function<double(int i, const VecX<double>& q)> frame;
};

double cost(const Model& model, Data& data, Formulation f, const OcpWeights& w, const VecX<double>& q_ref_fixed,
            const VecX<double>& u_ref_fixed, const Bounds& bounds, const VecX<double>& U, VecX<double> q,
            VecX<double> v, double T, int N, const VecX<double>& d_hat = VecX<double>(),
            const StageReferences* moving = nullptr) {
  const int n = model.n, m = bounds.m(), sd = n + 2 * m;
  const VecX<double> dist = d_hat.size() == 0 ? VecX<double>::Zero(n) : d_hat;
  const double dtau = T / N;
  VecX<double> q_ref = q_ref_fixed, v_ref = VecX<double>::Zero(n), u_ref = u_ref_fixed;
  auto phi = [&](int i, const VecX<double>& qi, const VecX<double>& vi) {
    if (moving) moving->joint(i, q_ref, v_ref, u_ref);
    const VecX<double> e = qi - q_ref, ev = vi - v_ref;
    return 0.5 * e.dot(w.Qq.cwiseProduct(e)) + 0.5 * ev.dot(w.Qv.cwiseProduct(ev)) +
           (moving ? moving->frame(i, qi) : 0.0);
  };
  double J = 0;
  for (int i = 0; i < N; ++i) {
    VecX<double> a(n), u(n);
    if (f == Formulation::kForwardDynamics) {
      u = U.segment(i * sd, n);
      a = aba(model, data, q, v, VecX<double>(u + dist));
    } else {
      a = U.segment(i * sd, n);
      u = rnea(model, data, q, v, a) - dist;
    }
    double L = phi(i, q, v);  // sets stage i's u_ref
    const VecX<double> e = u - u_ref;
    L += 0.5 * e.dot(w.R.cwiseProduct(e));
    if (f == Formulation::kInverseDynamics) L += 0.5 * a.dot(w.Qa.cwiseProduct(a));
    for (int k = 0; k < m; ++k) {
      const double d = U[i * sd + n + k], rho = U[i * sd + n + m + k];
      const double du = u[bounds.joint[static_cast<size_t>(k)]] - bounds.middle[k];
      L += rho * bounds.scale[k] * (du * du + d * d - bounds.half_range[k] * bounds.half_range[k]) -
           bounds.r_d[k] * d;
    }
    J += dtau * L;
    const VecX<double> q_next = q + dtau * v;
    v += dtau * a;
    q = q_next;
  }
  return J + phi(N, q, v);
}

// the torque that holds q_ref: gravity and springs at rest
VecX<double> holding_torque(const Model& model, Data& data, const VecX<double>& q_ref) {
  const VecX<double> zero = VecX<double>::Zero(model.n);
  return rnea(model, data, q_ref, zero, zero);
}

// the stage torques u_i = ID(q_i, v_i, a_i) − d̂ along the explicit-Euler rollout of
// accelerations A (d̂ empty: none)
VecX<double> torques_of(const Model& model, Data& data, const VecX<double>& A, VecX<double> q,
                        VecX<double> v, double T, int N, const VecX<double>& d_hat = VecX<double>()) {
  const int n = model.n;
  const double dtau = T / N;
  VecX<double> U(N * n);
  for (int i = 0; i < N; ++i) {
    U.segment(i * n, n) = rnea(model, data, q, v, A.segment(i * n, n));
    if (d_hat.size() != 0) U.segment(i * n, n) -= d_hat;
    const VecX<double> q_next = q + dtau * v;
    v += dtau * A.segment(i * n, n);
    q = q_next;
  }
  return U;
}

class OcpGradient
    : public ::testing::TestWithParam<std::tuple<std::string, Formulation, DerivativeMode>> {};

TEST_P(OcpGradient, ResidualIsTheScaledGradientOfTheDiscreteCost) {
  const auto& [path, formulation_binding, mode] = GetParam();
  const Formulation formulation = formulation_binding;  // a variable the lambdas may capture (C++17)
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
    Shooting ocp(p.model, formulation, mode, w, q_ref, N);
    VecX<double> F(N * n);
    ocp.residual(U, q0, v0, T, F);

    const VecX<double> u_ref = holding_torque(p.model, data, q_ref);
    const MatX<double> grad = central_difference_jacobian(
        [&](const VecX<double>& X) {
          return VecX<double>::Constant(
              1, cost(p.model, data, formulation, w, q_ref, u_ref, Bounds{}, X, q0, v0, T, N));
        },
        U);
    const VecX<double> expected = grad.row(0).transpose() / (T / N);
    EXPECT_LE((F - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kGradientMatch)
        << "F        " << F.transpose() << "\nexpected " << expected.transpose();
  }
}

// A target set between evaluations (OcpProblem::set_target) is the target of the next residual:
// F is the gradient of the cost with the new q_ref and its torque reference ID(q_ref, 0, 0) − d̂,
// after an evaluation with the old target, with a disturbance estimate set before, stages in lanes
// and stage by stage.
TEST_P(OcpGradient, AfterSetTargetResidualIsTheGradientWithTheNewTarget) {
  const auto& [path, formulation_binding, mode] = GetParam();
  const Formulation formulation = formulation_binding;
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 6;
  const double T = 0.3;
  Data data(p.model);
  std::mt19937 rng(11);
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                     random_vector(rng, n, 1e-3, 1e-2), random_vector(rng, n, 1e-4, 1e-3)};
  const VecX<double> old_target = random_vector(rng, n, -0.5, 0.5), target = random_vector(rng, n, -0.5, 0.5);
  const VecX<double> d_hat = random_vector(rng, n, 0.5);
  const VecX<double> q0 = random_vector(rng, n, -2.0, 2.0), v0 = random_vector(rng, n, -1.0, 1.0);
  const VecX<double> A = random_vector(rng, N * n, -3.0, 3.0);
  const VecX<double> U =
      formulation == Formulation::kInverseDynamics ? A : torques_of(p.model, data, A, q0, v0, T, N, d_hat);
  const VecX<double> u_ref = holding_torque(p.model, data, target) - d_hat;
  const MatX<double> grad = central_difference_jacobian(
      [&](const VecX<double>& X) {
        return VecX<double>::Constant(
            1, cost(p.model, data, formulation, w, target, u_ref, Bounds{}, X, q0, v0, T, N, d_hat));
      },
      U);
  const VecX<double> expected = grad.row(0).transpose() / (T / N);
  for (bool lanes : {true, false}) {
    SCOPED_TRACE(lanes ? "lanes" : "stage by stage");
    Shooting ocp(p.model, formulation, mode, w, old_target, N);
    ocp.set_stage_batching(lanes);
    ocp.problem().set_disturbance(d_hat);
    VecX<double> F(N * n);
    ocp.residual(U, q0, v0, T, F);
    ocp.problem().set_target(target);
    EXPECT_EQ(ocp.problem().cost().q_ref(), target);
    ocp.residual(U, q0, v0, T, F);
    EXPECT_LE((F - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kGradientMatch)
        << "F        " << F.transpose() << "\nexpected " << expected.transpose();
  }
  // sizes and finiteness are checked
  OcpProblem problem(p.model, formulation, mode, w, old_target, N);
  EXPECT_THROW(problem.set_target(VecX<double>::Zero(n + 1)), std::invalid_argument);
  EXPECT_THROW(problem.set_target(VecX<double>::Constant(n, std::nan(""))), std::invalid_argument);
  EXPECT_EQ(problem.cost().q_ref(), old_target);
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

// Torque limits (formulations.md §Torque limits): the residual is the gradient of the augmented cost — the
// Lagrangian with ρᵀc − r_dᵀd per stage — with respect to every unknown: inputs, dummy inputs and
// multipliers, F_i = (1/Δτ) ∂J/∂(input_i, d_i, ρ_i). Some joints unbounded, some bounded with
// the torque of a stage exactly at the bound, the others' limits narrower than the torques;
// ID adjoint both in SIMD lanes and stage by stage.
TorqueLimits limits_around(const VecX<double>& Utorque, int n, int N) {
  const double inf = std::numeric_limits<double>::infinity();
  TorqueLimits limits{VecX<double>::Constant(n, -inf), VecX<double>::Constant(n, inf)};
  for (int j = 1; j < n; j += 2) {
    double lo = inf, hi = -inf;
    for (int i = 0; i < N; ++i) {
      lo = std::min(lo, Utorque[i * n + j]);
      hi = std::max(hi, Utorque[i * n + j]);
    }
    // every other bounded joint: its largest torque exactly at the upper bound (d = 0 solves
    // c there), the others: a range narrower than the torques (c < 0 unreachable, c > 0 seen)
    if (j % 4 == 1) {
      limits.lower[j] = lo - 1.0;
      limits.upper[j] = hi;
    } else {
      limits.lower[j] = 0.75 * lo + 0.25 * hi;
      limits.upper[j] = 0.25 * lo + 0.75 * hi + 1e-3;
    }
  }
  return limits;
}

constexpr double kExactStepScale = 1e4;

// each part of F against its own scale: the constraint values c (torque²) would hide an error
// in the input part
double part_error(const VecX<double>& F, const VecX<double>& expected, int N, int sd, int offset, int size) {
  double err = 0, scale = 0;
  for (int i = 0; i < N; ++i) {
    err = std::max(err, (F.segment(i * sd + offset, size) - expected.segment(i * sd + offset, size)).cwiseAbs().maxCoeff());
    scale = std::max(scale, expected.segment(i * sd + offset, size).cwiseAbs().maxCoeff());
  }
  return err / std::max(scale, 1e-12);
}

TEST_P(OcpGradient, WithTorqueLimitsResidualIsTheGradientOfTheAugmentedCost) {
  const auto& [path, formulation_binding, mode] = GetParam();
  const Formulation formulation = formulation_binding;  // a variable the lambdas may capture (C++17)
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 6;
  const double T = 0.3;
  Data data(p.model);
  for (unsigned seed = 1; seed <= 3; ++seed) {
    std::mt19937 rng(seed);
    const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                       random_vector(rng, n, 1e-3, 1e-2), random_vector(rng, n, 1e-4, 1e-3)};
    const VecX<double> q_ref = random_vector(rng, n, -0.5, 0.5);
    const VecX<double> q0 = random_vector(rng, n, -2.0, 2.0), v0 = random_vector(rng, n, -1.0, 1.0);
    const VecX<double> A = random_vector(rng, N * n, -3.0, 3.0);
    const VecX<double> Utorque = torques_of(p.model, data, A, q0, v0, T, N);
    const TorqueLimits limits = limits_around(Utorque, n, N);
    for (const bool lanes : {true, false}) {
      Shooting ocp(p.model, formulation, mode, w, q_ref, N, limits);
      ocp.set_stage_batching(lanes);
      if (lanes != ocp.stage_batching()) continue;  // lanes: ID adjoint only
      SCOPED_TRACE("seed " + std::to_string(seed) + (lanes ? ", lanes" : ", stage by stage"));
      const int m = ocp.problem().m(), sd = ocp.stage_dim();
      ASSERT_EQ(m, n / 2);
      ASSERT_EQ(ocp.dim(), N * (n + 2 * m));
      // dummy inputs from near 0 (the bound reached) to the half range, multipliers of both signs
      // and of the magnitudes the solution sees (ρ ≈ r_d / 2sd ≈ κΔ/2d)
      VecX<double> U(N * sd);
      const Bounds b = bounds_of(limits, w.R, ocp.problem().torque_bounds().r_d());
      for (int i = 0; i < N; ++i) {
        U.segment(i * sd, n) = formulation == Formulation::kInverseDynamics ? A.segment(i * n, n)
                                                                             : Utorque.segment(i * n, n);
        U.segment(i * sd + n, m) = random_vector(rng, m, 1e-3, 1.0).cwiseProduct(b.half_range);
        U.segment(i * sd + n + m, m) = random_vector(rng, m, -1.0, 10.0);
      }
      VecX<double> F(N * sd);
      ocp.residual(U, q0, v0, T, F);

      // J is quadratic in d and linear in ρ, where central differences have no truncation error:
      // differentiated in d/σ and ρ/σ, so that their steps are σ times the default and J's
      // rounding (ε|J|/step) stays far below their small gradients (r_d ≈ 1e-6 here)
      const VecX<double> u_ref = holding_torque(p.model, data, q_ref);
      VecX<double> sigma = VecX<double>::Ones(N * sd);
      for (int i = 0; i < N; ++i) sigma.segment(i * sd + n, 2 * m).setConstant(kExactStepScale);
      const MatX<double> grad = central_difference_jacobian(
          [&](const VecX<double>& X) {
            const VecX<double> Y = X.cwiseProduct(sigma);
            return VecX<double>::Constant(1, cost(p.model, data, formulation, w, q_ref, u_ref, b, Y, q0, v0, T, N));
          },
          VecX<double>(U.cwiseQuotient(sigma)));
      const VecX<double> expected = grad.row(0).transpose().cwiseQuotient(sigma) / (T / N);
      EXPECT_LE(part_error(F, expected, N, sd, 0, n), kGradientMatch) << "inputs";
      EXPECT_LE(part_error(F, expected, N, sd, n, m), kGradientMatch) << "dummy inputs";
      EXPECT_LE(part_error(F, expected, N, sd, n + m, m), kGradientMatch) << "multipliers";
    }
  }
}

// Joint friction f·tanh(v/ε) and a disturbance estimate d̂ (formulations.md §Passive forces): the model's joint torque
// is u + d̂, so the cost rolled out here uses a = FD(q, v, u + d̂) (FD) and u = ID(q, v, a) − d̂
// (ID), with u_ref = ID(q_ref, 0, 0) − d̂ and the torque limits on u; the model has friction
// on most joints (random f in [0.1, 2], ε in [0.01, 0.5], every third joint none). Half the
// joints move slowly, |v| ≲ 2ε over the whole horizon, where the friction's slope f/ε·sech²(v/ε)
// dominates ∂ID/∂v; the others fast, where tanh saturates and only the force ±f is seen.
// For every formulation and derivative mode, with and without torque limits, stages in SIMD
// lanes and stage by stage: F is (1/Δτ) ∂J/∂U, single shooting's and multiple shooting's at the
// rollout (there FD adjoint runs its stages in lanes at the stored costates), and the stage
// torques of the rollout are u = ID − d̂.
//
// FD's rollout integrates the friction explicitly: near v = 0 its slope acts as a damping f/ε, and
// with Δτ·(f/ε)·(M⁻¹)_jj ≫ 1 the Euler step amplifies velocity perturbations by that factor per
// stage (measured: F ~ 1e12 on tree.xml, whose light bodies have (M⁻¹)_jj ~ 1e2–1e3, and J(U) so
// nonlinear that no central difference resolves it). The horizon setup (horizon_setup.cpp) keeps
// ε ≥ Δτ·f·(M⁻¹)_jj for that reason; where FD is involved, the test's ε obeys the same floor at q0.
struct FrictionDraw {
  VecX<double> f, eps;
};

FrictionDraw draw_friction(std::mt19937& rng, int n) {
  FrictionDraw d{random_vector(rng, n, 0.1, 2.0), random_vector(rng, n, std::log(0.01), std::log(0.5))};
  d.eps = d.eps.array().exp();  // log-uniform
  for (int j = 1; j < n; j += 3) {
    d.f[j] = 0;
    d.eps[j] = 0;
  }
  return d;
}

// ε_j ≥ Δτ·f_j·(M(q)⁻¹)_jj: the explicit horizon step stable at q (as horizon_setup.cpp chooses it)
void stable_friction_velocity(const Model& model, const VecX<double>& q, double dtau, FrictionDraw& d) {
  Data data(model);
  const VecX<double> minv_diag = minv_matrix(model, data, q).diagonal();
  for (int j = 0; j < model.n; ++j) {
    if (d.f[j] > 0) d.eps[j] = std::max(d.eps[j], dtau * d.f[j] * minv_diag[j]);
  }
}

// joint j slow (j even: |v| ≤ 2ε over the horizon, ε capped at 0.5 where the floor above raised
// it) or fast (|v| up to 1 + 3T); initial velocities and accelerations of the horizon
void friction_test_motion(std::mt19937& rng, const VecX<double>& eps, int N, double T, VecX<double>& v0,
                          VecX<double>& A) {
  const int n = static_cast<int>(eps.size());
  v0 = random_vector(rng, n, -1.0, 1.0);
  A = random_vector(rng, N * n, -3.0, 3.0);
  for (int j = 0; j < n; j += 2) {
    const double e = eps[j] > 0 ? std::min(eps[j], 0.5) : 0.1;
    v0[j] *= e;
    for (int i = 0; i < N; ++i) A[i * n + j] *= e / (3.0 * T);  // Σ Δτ|a| ≤ ε
  }
}

TEST_P(OcpGradient, WithFrictionAndDisturbanceResidualIsTheGradientOfTheCost) {
  const auto& [path, formulation_binding, mode] = GetParam();
  const Formulation formulation = formulation_binding;  // a variable the lambdas may capture (C++17)
  const Problem p = load_problem(path);
  const int n = p.model.n, N = 6;
  const double T = 0.3;
  for (unsigned seed = 1; seed <= 2; ++seed) {
    std::mt19937 rng(100 + seed);
    FrictionDraw fr = draw_friction(rng, n);
    const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                       random_vector(rng, n, 1e-3, 1e-2), random_vector(rng, n, 1e-4, 1e-3)};
    const VecX<double> q_ref = random_vector(rng, n, -0.5, 0.5), q0 = random_vector(rng, n, -2.0, 2.0);
    if (formulation == Formulation::kForwardDynamics) stable_friction_velocity(p.model, q0, T / N, fr);
    const Model model = with_joint_friction(p.model, fr.f, fr.eps);
    Data data(model);
    VecX<double> v0, A;
    friction_test_motion(rng, fr.eps, N, T, v0, A);
    // of the order of the holding torques, and of both signs
    const VecX<double> d_hat = random_vector(rng, n, -3.0, 3.0);
    const VecX<double> Utorque = torques_of(model, data, A, q0, v0, T, N, d_hat);
    const VecX<double> u_ref = holding_torque(model, data, q_ref) - d_hat;
    for (const bool limited : {false, true}) {
      const TorqueLimits limits = limited ? limits_around(Utorque, n, N) : TorqueLimits{};
      for (const bool lanes : {true, false}) {
        SCOPED_TRACE("seed " + std::to_string(seed) + (limited ? ", torque limits" : ", no limits") +
                     (lanes ? ", lanes" : ", stage by stage"));
        Shooting ocp(model, formulation, mode, w, q_ref, N, limits);
        ocp.set_stage_batching(lanes);
        ocp.problem().set_disturbance(d_hat);
        ASSERT_EQ(ocp.problem().disturbance(), d_hat);
        EXPECT_LE((ocp.problem().terms().u_ref(0) - u_ref).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, u_ref.norm()))
            << "u_ref = ID(q_ref, 0, 0) - d_hat";
        const int m = ocp.problem().m(), sd = ocp.stage_dim();
        ASSERT_EQ(m, limited ? n / 2 : 0);
        const Bounds b = limited ? bounds_of(limits, w.R, ocp.problem().torque_bounds().r_d()) : Bounds{};
        VecX<double> U(N * sd);
        for (int i = 0; i < N; ++i) {
          const VecX<double>& input = formulation == Formulation::kInverseDynamics ? A : Utorque;
          U.segment(i * sd, n) = input.segment(i * n, n);
          if (m > 0) {
            U.segment(i * sd + n, m) = random_vector(rng, m, 1e-3, 1.0).cwiseProduct(b.half_range);
            U.segment(i * sd + n + m, m) = random_vector(rng, m, -1.0, 10.0);
          }
        }
        VecX<double> F(N * sd);
        ocp.residual(U, q0, v0, T, F);
        // the stage torques of the rollout: the actuators' u = ID − d̂ (ID: unpacked from the lanes)
        EXPECT_LE((Eigen::Map<const VecX<double>>(ocp.torques().data(), N * n) - Utorque).cwiseAbs().maxCoeff(),
                  1e-10 * std::max(1.0, Utorque.cwiseAbs().maxCoeff()))
            << "stage torques";

        // as in the torque-limit test: d and ρ differentiated with σ-times larger steps
        VecX<double> sigma = VecX<double>::Ones(N * sd);
        for (int i = 0; i < N; ++i) sigma.segment(i * sd + n, 2 * m).setConstant(kExactStepScale);
        const MatX<double> grad = central_difference_jacobian(
            [&](const VecX<double>& X) {
              const VecX<double> Y = X.cwiseProduct(sigma);
              return VecX<double>::Constant(1, cost(model, data, formulation, w, q_ref, u_ref, b, Y, q0, v0, T, N, d_hat));
            },
            VecX<double>(U.cwiseQuotient(sigma)));
        const VecX<double> expected = grad.row(0).transpose().cwiseQuotient(sigma) / (T / N);
        EXPECT_LE(part_error(F, expected, N, sd, 0, n), kGradientMatch)
            << "inputs\nF        " << F.transpose() << "\nexpected " << expected.transpose();
        if (m > 0) {
          EXPECT_LE(part_error(F, expected, N, sd, n, m), kGradientMatch) << "dummy inputs";
          EXPECT_LE(part_error(F, expected, N, sd, n + m, m), kGradientMatch) << "multipliers";
        }

        // multiple shooting at the rollout: zero defects and the same gradient
        const ShootingTrajectory rollout = ocp.trajectory();
        ShootingDefects e;
        e.resize(n, N);
        VecX<double> Fm(N * sd);
        ocp.residual_at(U, rollout, q0, v0, T, Fm, e);
        EXPECT_LE(part_error(Fm, expected, N, sd, 0, n), kGradientMatch) << "inputs, multiple shooting";
        if (m > 0) {
          EXPECT_LE(part_error(Fm, expected, N, sd, n + m, m), kGradientMatch) << "multipliers, multiple shooting";
        }
        EXPECT_LE(std::sqrt(e.v.squaredNorm()), 1e-10 * std::max(1.0, rollout.v.norm())) << "velocity defects";
      }
    }
  }
}

// A moving target, independent of the library's shapes: value c + a∘sin(ωt + φ), rate aω∘cos(ωt + φ).
class SineTrajectory final : public Trajectory {
 public:
  SineTrajectory(VecX<double> c, VecX<double> a, double omega, VecX<double> phase)
      : c_(std::move(c)), a_(std::move(a)), omega_(omega), phase_(std::move(phase)) {}
  std::unique_ptr<Trajectory> clone() const override { return std::make_unique<SineTrajectory>(*this); }
  int dim() const override { return static_cast<int>(c_.size()); }
  void sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const override {
    const VecX<double> arg = (omega_ * t + phase_.array()).matrix();
    value = c_ + a_.cwiseProduct(VecX<double>(arg.array().sin()));
    rate = omega_ * a_.cwiseProduct(VecX<double>(arg.array().cos()));
  }
  std::string describe() const override { return "sine"; }

 private:
  VecX<double> c_, a_;
  double omega_;
  VecX<double> phase_;
};

SineTrajectory random_sine(std::mt19937& rng, int dim, double centre, double amplitude) {
  return SineTrajectory(random_vector(rng, dim, centre), random_vector(rng, dim, 0.2 * amplitude, amplitude),
                        std::uniform_real_distribution<double>(1.0, 4.0)(rng), random_vector(rng, dim, 3.0));
}

// A frame target and references that move (StageTerms): stage i's joint target, its rate and
// torque reference are those at t0 + i·Δτ, the frame's position target too, and the frame cost
// ½(p − p_ref)ᵀdiag(w_p)(p − p_ref) + w_o(1 − cos θ) is evaluated here with MuJoCo's kinematics
// (mj_kinematics: the body's xpos and xmat) — F is the gradient of that cost, in both shooting
// schemes, stages in lanes and stage by stage.
TEST_P(OcpGradient, WithAFrameTargetAndMovingReferencesResidualIsTheGradient) {
  const auto& [path, formulation_binding, mode] = GetParam();
  const Formulation formulation = formulation_binding;
  const Problem p = load_problem(path);
  const bool arm4 = path.find("arm4") != std::string::npos;
  const std::string body = arm4 ? "link3" : "right_hand";
  const int b = mj_name2id(p.m.get(), mjOBJ_BODY, body.c_str());
  ASSERT_GE(b, 0);
  const int n = p.model.n, N = 6;
  const double T = 0.3, t0 = 0.7, dtau = T / N;
  Data data(p.model), ref_data(p.model);
  mj::DataPtr d = mj::make_data(p.m.get());
  std::mt19937 rng(21);
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2),
                     random_vector(rng, n, 1e-3, 1e-2), random_vector(rng, n, 1e-4, 1e-3)};
  FrameTarget target;
  target.frame = mj::import_frame(p.m.get(), body, path);
  target.position_weight = random_vector(rng, 3, 2.0, 8.0);
  target.orientation_weight = 3.0;
  target.rotation = Eigen::AngleAxisd(1.0, Vec3<double>(random_vector(rng, 3, 1.0).normalized())).toRotationMatrix();
  const auto joint = std::make_shared<SineTrajectory>(random_sine(rng, n, 0.5, 0.4));
  const auto frame = std::make_shared<SineTrajectory>(random_sine(rng, 3, 1.0, 0.3));
  const VecX<double> d_hat = random_vector(rng, n, 0.5);
  const VecX<double> q0 = random_vector(rng, n, -2.0, 2.0), v0 = random_vector(rng, n, -1.0, 1.0);
  const VecX<double> A = random_vector(rng, N * n, -3.0, 3.0);
  const VecX<double> U =
      formulation == Formulation::kInverseDynamics ? A : torques_of(p.model, data, A, q0, v0, T, N, d_hat);

  StageReferences moving;
  moving.joint = [&](int i, VecX<double>& q_ref, VecX<double>& v_ref, VecX<double>& u_ref) {
    joint->sample(t0 + i * dtau, q_ref, v_ref);
    u_ref = holding_torque(p.model, ref_data, q_ref) - d_hat;
  };
  moving.frame = [&](int i, const VecX<double>& q) {
    VecX<double> p_ref(3), rate(3);
    frame->sample(t0 + i * dtau, p_ref, rate);
    Eigen::Map<VecX<double>>(d->qpos, n) = q;
    mj_kinematics(p.m.get(), d.get());
    const Vec3<double> e = Eigen::Map<const Vec3<double>>(d->xpos + 3 * b) - p_ref;
    const Mat3<double> R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->xmat + 9 * b);
    return 0.5 * e.dot(target.position_weight.cwiseProduct(e)) +
           0.5 * target.orientation_weight * (3.0 - (target.rotation.transpose() * R).trace());
  };
  const VecX<double> unused = VecX<double>::Zero(n);
  const MatX<double> grad = central_difference_jacobian(
      [&](const VecX<double>& X) {
        return VecX<double>::Constant(
            1, cost(p.model, data, formulation, w, unused, unused, Bounds{}, X, q0, v0, T, N, d_hat, &moving));
      },
      U);
  const VecX<double> expected = grad.row(0).transpose() / dtau;
  for (bool lanes : {true, false}) {
    SCOPED_TRACE(lanes ? "lanes" : "stage by stage");
    Shooting ocp(p.model, formulation, mode, w, unused, N);
    ocp.set_stage_batching(lanes);
    ocp.problem().set_disturbance(d_hat);
    ocp.problem().set_frame_target(target);
    ocp.problem().set_frame_trajectory(frame);
    ocp.problem().set_joint_trajectory(joint);
    ocp.set_time(t0);
    VecX<double> F(N * n);
    ocp.residual(U, q0, v0, T, F);
    EXPECT_LE((F - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kGradientMatch)
        << "F        " << F.transpose() << "\nexpected " << expected.transpose();
    // multiple shooting at the rollout: zero defects and the same gradient
    const ShootingTrajectory rollout = ocp.trajectory();
    ShootingDefects e;
    e.resize(n, N);
    VecX<double> Fm(N * n);
    ocp.residual_at(U, rollout, q0, v0, T, Fm, e);
    EXPECT_LE((Fm - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kGradientMatch)
        << "multiple shooting";
    // the references are those of the time set: later, another residual
    ocp.set_time(t0 + 0.1);
    ocp.residual(U, q0, v0, T, F);
    EXPECT_GT((F - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), 1e-3) << "at t0 + 0.1";
  }
}

// set_disturbance takes n finite values
// the task's stage cost that closed loops integrate (StageTerms::stage_cost): its gradients are
// the ones the residual is built from (state_gradient, and R(u − u_ref) without limits), and it
// vanishes at the target (the frame at its pose, at rest, holding torque)
TEST(StageCost, GradientsOfTheValueAreTheStageGradientsAndTheTargetCostsNothing) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/panda.xml");
  const int n = p.model.n;
  std::mt19937 rng(4);
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2), VecX<double>::Zero(n),
                     random_vector(rng, n, 1e-3, 1e-2)};
  const VecX<double> q_ref = random_vector(rng, n, 1.0);
  StageTerms terms(std::make_shared<const Model>(p.model), QuadraticCost(w, q_ref, n), TorqueLimits{}, 4, false);
  FrameTarget target;
  target.frame = Frame{"flange", n - 1, Transform<double>{}};
  target.position_weight = random_vector(rng, 3, 2.0, 8.0);
  target.orientation_weight = 3.0;
  FrameKinematics<double> fk(p.model, target.frame);
  fk.compute(p.model, q_ref);
  target.position = fk.position();
  target.rotation = fk.rotation();
  terms.set_frame_target(target);
  const VecX<double> zero = VecX<double>::Zero(n);
  EXPECT_NEAR(terms.stage_cost(1, q_ref, zero, terms.u_ref(1)), 0.0, 1e-14);

  const VecX<double> q = random_vector(rng, n, 1.0), v = random_vector(rng, n, 1.0), u = random_vector(rng, n, 5.0);
  VecX<double> L_q(n), L_v(n);
  StageTerms::FrameScratch<double> scratch;
  terms.state_gradient(1, q, v, L_q, L_v, scratch);
  const VecX<double> L_u = w.R.cwiseProduct(u - terms.u_ref(1));
  auto gradient = [&](int which) {
    VecX<double> g(n);
    const double h = 1e-6;
    for (int j = 0; j < n; ++j) {
      VecX<double> x[3] = {q, v, u}, y[3] = {q, v, u};
      x[which][j] += h;
      y[which][j] -= h;
      g[j] = (terms.stage_cost(1, x[0], x[1], x[2]) - terms.stage_cost(1, y[0], y[1], y[2])) / (2 * h);
    }
    return g;
  };
  EXPECT_LE((gradient(0) - L_q).norm(), 1e-7 * (1 + L_q.norm()));
  EXPECT_LE((gradient(1) - L_v).norm(), 1e-7 * (1 + L_v.norm()));
  EXPECT_LE((gradient(2) - L_u).norm(), 1e-7 * (1 + L_u.norm()));
}

// a panda problem whose joint target and frame target both move (waypoints), d̂ set
StageTerms moving_panda_terms(const Problem& p, int N) {
  const int n = p.model.n;
  std::mt19937 rng(6);
  const OcpWeights w{random_vector(rng, n, 0.5, 2.0), random_vector(rng, n, 0.05, 0.2), VecX<double>::Zero(n),
                     random_vector(rng, n, 1e-3, 1e-2)};
  StageTerms terms(std::make_shared<const Model>(p.model), QuadraticCost(w, random_vector(rng, n, 1.0), n),
                   TorqueLimits{}, N, false);
  FrameTarget target;
  target.frame = Frame{"flange", n - 1, Transform<double>{}};
  target.position_weight = random_vector(rng, 3, 2.0, 8.0);
  target.orientation_weight = 3.0;
  target.position = Vec3<double>(0.4, 0.1, 0.5);
  terms.set_frame_target(target);
  MatX<double> joints(n, 3), points(3, 3);
  for (int k = 0; k < 3; ++k) {
    joints.col(k) = random_vector(rng, n, 1.0);
    points.col(k) = Vec3<double>(0.4, 0.1, 0.5) + random_vector(rng, 3, 0.1);
  }
  terms.set_joint_trajectory(std::make_shared<WaypointTrajectory>(std::vector<double>{0.0, 0.3, 0.7}, joints));
  terms.set_frame_trajectory(std::make_shared<WaypointTrajectory>(std::vector<double>{0.0, 0.4, 0.8}, points));
  terms.set_disturbance(random_vector(rng, n, 2.0));
  return terms;
}

// stage_cost_at(t) is stage i's cost when stage i's time is t, whatever stage times were set
// last; and at another time it differs (the references move)
TEST(StageCost, AtATimeIsTheStageCostOfThatTime) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/panda.xml");
  const int n = p.model.n;
  StageTerms terms = moving_panda_terms(p, 4);
  std::mt19937 rng(8);
  const VecX<double> q = random_vector(rng, n, 1.0), v = random_vector(rng, n, 1.0), u = random_vector(rng, n, 5.0);
  StageTerms::CostScratch scratch = terms.cost_scratch();
  const double t0 = 0.13, dtau = 0.05;
  terms.set_stage_times(t0, dtau);
  std::vector<double> at_stage;
  for (int i = 0; i <= 4; ++i) at_stage.push_back(terms.stage_cost(i, q, v, u));
  terms.set_stage_times(0.61, 0.02);  // elsewhere: stage_cost_at must not depend on it
  for (int i = 0; i <= 4; ++i) {
    const double t = t0 + i * dtau;
    EXPECT_NEAR(terms.stage_cost_at(t, q, v, u, scratch), at_stage[static_cast<size_t>(i)],
                1e-12 * at_stage[static_cast<size_t>(i)])
        << "t = " << t;
    EXPECT_GT(std::abs(terms.stage_cost(i, q, v, u) - at_stage[static_cast<size_t>(i)]),
              1e-6 * at_stage[static_cast<size_t>(i)]);
  }
}

// The const stage functions share no scratch: two threads evaluating one problem's state
// gradients (with the frame's Jᵀf) and costs at different states, each in its own
// workspace, get what one thread gets alone
TEST(StageTermsThreads, ConstFunctionsOfOneProblemRunConcurrently) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/panda.xml");
  const int n = p.model.n;
  const StageTerms terms = moving_panda_terms(p, 4);
  constexpr int kStates = 64, kRounds = 300;
  std::mt19937 rng(9);
  std::vector<VecX<double>> qs, vs;
  for (int k = 0; k < kStates; ++k) {
    qs.push_back(random_vector(rng, n, 2.0));
    vs.push_back(random_vector(rng, n, 1.0));
  }
  struct Out {
    std::vector<VecX<double>> L_q;
    std::vector<double> cost;
  };
  auto evaluate = [&](int first) {
    Out out;
    StageTerms::FrameScratch<double> scratch;
    VecX<double> L_q(n), L_v(n);
    for (int r = 0; r < kRounds; ++r) {
      for (int j = 0; j < kStates; ++j) {
        const int k = (first + j) % kStates;
        terms.state_gradient(2, qs[static_cast<size_t>(k)], vs[static_cast<size_t>(k)], L_q, L_v, scratch);
        const double c = terms.stage_cost(2, qs[static_cast<size_t>(k)], vs[static_cast<size_t>(k)], L_v);
        if (r == 0) {
          out.L_q.push_back(L_q);
          out.cost.push_back(c);
        } else if (out.L_q[static_cast<size_t>(j)] != L_q || out.cost[static_cast<size_t>(j)] != c) {
          out.cost[static_cast<size_t>(j)] = std::numeric_limits<double>::quiet_NaN();
        }
      }
    }
    return out;
  };
  const Out alone = evaluate(0);
  Out a, b;
  std::thread other([&] { b = evaluate(kStates / 2); });
  a = evaluate(0);
  other.join();
  for (int j = 0; j < kStates; ++j) {
    const size_t k = static_cast<size_t>(j), kb = static_cast<size_t>((j + kStates / 2) % kStates);
    EXPECT_EQ(a.L_q[k], alone.L_q[k]) << "state " << j;
    EXPECT_EQ(a.cost[k], alone.cost[k]) << "state " << j;
    EXPECT_EQ(b.L_q[k], alone.L_q[kb]) << "state " << j << " (second thread)";
    EXPECT_EQ(b.cost[k], alone.cost[kb]) << "state " << j << " (second thread)";
  }
}

TEST(OcpDisturbance, RefusesWrongSizeAndNonFiniteValues) {
  const Problem p = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const int n = p.model.n;
  OcpProblem ocp(p.model, Formulation::kInverseDynamics, DerivativeMode::kAdjoint, paper_weights(n),
                 VecX<double>::Zero(n), 5);
  EXPECT_EQ(ocp.disturbance(), VecX<double>::Zero(n)) << "zero until set";
  EXPECT_THROW(ocp.set_disturbance(VecX<double>::Zero(n + 1)), std::invalid_argument);
  EXPECT_THROW(ocp.set_disturbance(VecX<double>::Zero(n - 1)), std::invalid_argument);
  VecX<double> bad = VecX<double>::Zero(n);
  bad[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ocp.set_disturbance(bad), std::invalid_argument);
  bad[1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ocp.set_disturbance(bad), std::invalid_argument);
  EXPECT_EQ(ocp.disturbance(), VecX<double>::Zero(n)) << "a refused value must not be kept";
}

// u_ref = ID(q_ref, 0, 0) removes the gravity (and spring) offset: at rest at the target, the
// trajectory that stays there — a = 0 in ID, u = u_ref in FD — is stationary, F = 0, although
// the holding torque is far from zero.
// relative to R·u_ref, the residual without the reference: rounding only, measured up to 2e-8
// (FD on tree.xml, whose light bodies turn the rounding of FD(q_ref, 0, u_ref) into accelerations)
constexpr double kStationary = 1e-7;

TEST(OcpTorqueReference, RestAtTheTargetUnderGravityIsStationary) {
  for (const std::string path : {IDMPC_SOURCE_DIR "/mjcf/arm4.xml", IDMPC_SOURCE_DIR "/mjcf/tree.xml",
                                 IDMPC_SOURCE_DIR "/mjcf/panda.xml"}) {
    const Problem p = load_problem(path);
    const int n = p.model.n, N = 10;
    Data data(p.model);
    std::mt19937 rng(7);
    const VecX<double> q_ref = random_vector(rng, n, -1.0, 1.0), zero = VecX<double>::Zero(n);
    const VecX<double> u_ref = holding_torque(p.model, data, q_ref);
    ASSERT_GT(u_ref.cwiseAbs().maxCoeff(), 1.0) << path << ": the target must need a holding torque";
    for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      for (const DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
        SCOPED_TRACE(path + " " + to_string(f) + " " + to_string(mode));
        const OcpWeights w = paper_weights(n, 1e-3);
        Shooting ocp(p.model, f, mode, w, q_ref, N);
        EXPECT_LE((ocp.problem().terms().u_ref(0) - u_ref).cwiseAbs().maxCoeff(), 1e-12);
        VecX<double> U(N * n);
        for (int i = 0; i < N; ++i) U.segment(i * n, n) = f == Formulation::kForwardDynamics ? u_ref : zero;
        VecX<double> F(N * n);
        ocp.residual(U, q_ref, zero, 0.5, F);
        const double scale = w.R.cwiseProduct(u_ref).cwiseAbs().maxCoeff();
        EXPECT_LE(F.cwiseAbs().maxCoeff(), kStationary * scale) << F.transpose();
      }
    }
  }
}

// With Q_a = 0 both problems minimize the same cost, in torques U or in accelerations A, and
// the rollout maps A ↦ U(A) one to one (u_i = ID(q_i, v_i, a_i)). By the chain rule, at the same
// trajectory F_ID = (∂U/∂A)ᵀ F_FD: the blocks are M(q_i) on the diagonal and the effect of a_i
// on later torques below it. Hence F_ID,N−1 = M(q_{N−1}) F_FD,N−1 on the last stage, and both
// vanish together, which is what "differ only by the factor M(q_i)" (formulations.md) means: the
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
        Shooting fd(p.model, Formulation::kForwardDynamics, mode, w, q_ref, N);
        Shooting id(p.model, Formulation::kInverseDynamics, mode, w, q_ref, N);
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

namespace idmpc {
namespace {

// The same chain rule with joint friction in the model and a disturbance estimate d̂ in both
// problems: U(A) is now u_i = ID(q_i, v_i, a_i) − d̂ with friction in ID, FD rolls out
// FD(q, v, u + d̂); F_ID = (∂U/∂A)ᵀ F_FD still holds (d̂ shifts U but not ∂U/∂A, and the two
// problems must shift u_ref alike), F_ID,N−1 = M(q_{N−1}) F_FD,N−1 on the last stage. Stages in
// lanes and stage by stage, both derivative modes. Half the joints slow (|v| ≲ 2ε), where the
// friction's slope enters ∂U/∂A through the later stages' velocities.
TEST(OcpFormulations, IdResidualIsFdResidualThroughTheChainRuleWithFrictionAndDisturbance) {
  for (const std::string path : {IDMPC_SOURCE_DIR "/mjcf/arm4.xml", IDMPC_SOURCE_DIR "/mjcf/tree.xml"}) {
    const Problem p = load_problem(path);
    const int n = p.model.n, N = 6;
    const double T = 0.3;
    for (unsigned seed = 1; seed <= 2; ++seed) {
      std::mt19937 rng(200 + seed);
      FrictionDraw fr = draw_friction(rng, n);
      const OcpWeights w{VecX<double>::Constant(n, 1.0), VecX<double>::Constant(n, 0.1), VecX<double>::Zero(n),
                         VecX<double>::Constant(n, 1e-4)};
      const VecX<double> q_ref = random_vector(rng, n, -0.5, 0.5), q0 = random_vector(rng, n, -2.0, 2.0);
      stable_friction_velocity(p.model, q0, T / N, fr);  // FD's rollout is part of the identity
      const Model model = with_joint_friction(p.model, fr.f, fr.eps);
      Data data(model);
      VecX<double> v0, A;
      friction_test_motion(rng, fr.eps, N, T, v0, A);
      const VecX<double> d_hat = random_vector(rng, n, -3.0, 3.0);
      const VecX<double> U = torques_of(model, data, A, q0, v0, T, N, d_hat);
      const MatX<double> dU_dA = central_difference_jacobian(
          [&](const VecX<double>& X) { return torques_of(model, data, X, q0, v0, T, N, d_hat); }, A);
      VecX<double> q = q0, v = v0;
      for (int i = 0; i < N - 1; ++i) {
        const VecX<double> q_next = q + (T / N) * v;
        v += (T / N) * A.segment(i * n, n);
        q = q_next;
      }
      const MatX<double> M_last = crba(model, data, q);
      for (DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
        for (const bool lanes : {true, false}) {
          SCOPED_TRACE(path + ", " + to_string(mode) + ", seed " + std::to_string(seed) +
                       (lanes ? ", lanes" : ", stage by stage"));
          Shooting fd(model, Formulation::kForwardDynamics, mode, w, q_ref, N);
          Shooting id(model, Formulation::kInverseDynamics, mode, w, q_ref, N);
          for (Shooting* s : {&fd, &id}) {
            s->set_stage_batching(lanes);
            s->problem().set_disturbance(d_hat);
          }
          VecX<double> Ffd(N * n), Fid(N * n);
          fd.residual(U, q0, v0, T, Ffd);
          id.residual(A, q0, v0, T, Fid);
          const VecX<double> expected = dU_dA.transpose() * Ffd;
          EXPECT_LE((Fid - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff(), kChainRule)
              << "F_ID     " << Fid.transpose() << "\nexpected " << expected.transpose();
          const VecX<double> last = M_last * Ffd.tail(n);
          EXPECT_LE((Fid.tail(n) - last).cwiseAbs().maxCoeff() / std::max(1.0, last.cwiseAbs().maxCoeff()),
                    kLastStage);
        }
      }
    }
  }
}

}  // namespace
}  // namespace idmpc
