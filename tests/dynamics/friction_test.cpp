// Smooth joint friction f·tanh(v/ε) (formulations.md §Passive forces) in every dynamics kernel: on shipped models
// (arm4, xarm7, tree) and seeded random trees made with with_joint_friction (random f in
// [0.1, 2], ε in [0.01, 0.5], some joints without friction), at random states whose joint
// velocities cover |v| ≪ ε (slope ≈ f/ε, where a dropped slope shows), |v| ≈ ε (curvature) and
// |v| ≫ ε (tanh saturated, the force ≈ ±f, where a dropped or mis-signed force shows):
//   * rnea's friction part, the difference of rnea with and without friction, is f·tanh(v/ε)
//     written out here;
//   * rnea_derivatives and aba_derivatives against central differences, aba inverts rnea;
//   * rnea_vjp is the transposed derivative matrices times w;
//   * the SIMD-pack instantiation (StagePack lanes, a different state in each) equals the double
//     kernels lane by lane;
//   * with_joint_friction refuses what it must.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/pack.hpp"
#include "support/lanes.hpp"
#include "support/problems.hpp"
#include "support/random_model.hpp"

namespace idmpc {
namespace {

// identities exact in real arithmetic: rounding in O(n·depth) flops, relative to the scale
// (as in dynamics_test.cpp)
constexpr double kRounding = 1e-10;
// central differences with h = ε^(1/3)·max(1, |x|): truncation h²·f'''/6 + rounding ε·f/h. The
// friction's third derivative is up to 2f/ε³ = 4e6 (f = 2, ε = 0.01): 2.4e-5 absolute, against
// a derivative matrix whose scale is then ≥ f/ε·sech²(1) ≈ 80 (dynamics_test's tolerance holds)
constexpr double kFiniteDifference = 1e-6;
// the friction part is one addition onto the bodies' torque, the bodies' part bitwise the same
// with and without friction: a few ulps of |τ|
constexpr double kFrictionPart = 8 * std::numeric_limits<double>::epsilon();
// the SIMD lanes run the double kernels' operations lane by lane; only the compiler's
// contraction into fused multiply-adds may differ (the brief's 1e-12 relative)
constexpr double kLanes = 1e-12;
constexpr int kRandomTrees = 8;
constexpr int kStates = 3;  // random states per case (kStates ≤ kStageLanes for the lane test)

struct Case {
  std::string label;
  std::string path;  // shipped file, or empty for a random tree
  unsigned seed;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.label; }

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const char* stem : {"arm4", "xarm7", "tree"}) {
    out.push_back({stem, std::string(IDMPC_SOURCE_DIR "/mjcf/") + stem + ".xml", 1});
  }
  for (unsigned s = 1; s <= kRandomTrees; ++s) out.push_back({"random_tree_seed" + std::to_string(s), "", s});
  return out;
}

struct Models {
  Model plain;     // as imported (armature, damping, stiffness), no friction
  Model friction;  // the same with joint friction
  VecX<double> f, eps;
};

std::unique_ptr<Models> make_models(const Case& c) {
  const mj::ModelPtr m = c.path.empty() ? mj::load_model_from_string(test::random_tree_mjcf(c.seed))
                                        : mj::load_model(c.path);
  Model plain = mj::import_model(m.get(), c.label).model;
  const int n = plain.n;
  std::mt19937 rng(100 + c.seed);
  std::uniform_real_distribution<double> uf(0.1, 2.0), ue(std::log(0.01), std::log(0.5));
  VecX<double> f(n), eps(n);
  for (int j = 0; j < n; ++j) {
    f[j] = uf(rng);
    eps[j] = std::exp(ue(rng));  // log-uniform: small ε (steep slope) as often as large
  }
  // every third joint without friction (ε = 0 there is allowed and must not be divided by)
  for (int j = 1; j < n; j += 3) {
    f[j] = 0;
    eps[j] = 0;
  }
  Model friction = with_joint_friction(plain, f, eps);
  return std::make_unique<Models>(Models{std::move(plain), std::move(friction), f, eps});
}

struct State {
  VecX<double> q, v, a, tau;
};

// joint j of state k in regime (j + k) % 3: |v| ≤ 0.05ε, ε/2 ≤ |v| ≤ 2ε, or |v| ≥ 10ε; every
// regime on every joint across the states, random signs
State random_state(const Models& ms, std::mt19937& rng, int k) {
  const Model& model = ms.friction;
  const int n = model.n;
  std::uniform_real_distribution<double> unit(-1.0, 1.0), pos(0.0, 1.0);
  State s;
  s.q = model.q_ref + test::random_vector(rng, n, 3.0);
  s.a = test::random_vector(rng, n, 5.0);
  s.tau = test::random_vector(rng, n, 5.0);
  s.v.resize(n);
  for (int j = 0; j < n; ++j) {
    const double e = ms.f[j] > 0 ? ms.eps[j] : 0.1;
    const double sign = unit(rng) < 0 ? -1.0 : 1.0;
    switch ((j + k) % 3) {
      case 0: s.v[j] = 0.05 * e * unit(rng); break;
      case 1: s.v[j] = sign * e * (0.5 + 1.5 * pos(rng)); break;
      default: s.v[j] = sign * (10 * e + 2 * pos(rng)); break;
    }
  }
  return s;
}

double max_abs(const MatX<double>& x) { return x.cwiseAbs().maxCoeff(); }
/// ‖x − y‖∞ / max(scale, 1)
double scaled_error(const MatX<double>& x, const MatX<double>& y, double scale) {
  return (x - y).cwiseAbs().maxCoeff() / std::max(scale, 1.0);
}

class Friction : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override { ms_ = make_models(GetParam()); }
  const Model& model() const { return ms_->friction; }
  int n() const { return ms_->friction.n; }
  std::vector<State> states() const {
    std::mt19937 rng(GetParam().seed);
    std::vector<State> out;
    for (int k = 0; k < kStates; ++k) out.push_back(random_state(*ms_, rng, k));
    return out;
  }
  std::unique_ptr<Models> ms_;
};

TEST_P(Friction, ModelCarriesTheGivenFriction) {
  EXPECT_EQ(model().friction, ms_->f);
  EXPECT_EQ(model().friction_velocity, ms_->eps);
  EXPECT_TRUE(ms_->plain.friction.isZero(0.0));
  EXPECT_GT((ms_->f.array() > 0).count(), 0);
  EXPECT_GT((ms_->f.array() == 0).count(), 0) << "some joints must be without friction";
}

// ID with friction minus ID without it is f·tanh(v/ε), the sign that opposes the motion; exactly
// zero on the joints without friction (their torque is bitwise the same)
TEST_P(Friction, RneaFrictionPartIsFTanhVOverEps) {
  Data with(model()), without(ms_->plain);
  const std::vector<State> ss = states();
  for (size_t k = 0; k < ss.size(); ++k) {
    SCOPED_TRACE("state " + std::to_string(k));
    const State& s = ss[k];
    const VecX<double> tau_f = rnea(model(), with, s.q, s.v, s.a);
    const VecX<double> tau_0 = rnea(ms_->plain, without, s.q, s.v, s.a);
    for (int j = 0; j < n(); ++j) {
      const double expected = ms_->f[j] > 0 ? ms_->f[j] * std::tanh(s.v[j] / ms_->eps[j]) : 0.0;
      if (ms_->f[j] == 0) {
        EXPECT_EQ(tau_f[j], tau_0[j]) << "joint " << j << " has no friction";
      } else {
        EXPECT_NEAR(tau_f[j] - tau_0[j], expected,
                    kFrictionPart * (std::abs(tau_0[j]) + std::abs(expected) + 1.0))
            << "joint " << j << ", v " << s.v[j] << ", eps " << ms_->eps[j];
      }
    }
  }
}

TEST_P(Friction, RneaDerivativesMatchFiniteDifferences) {
  Data data(model());
  for (const State& s : states()) {
    const VecX<double> tau = rnea(model(), data, s.q, s.v, s.a);
    rnea_derivatives(model(), data, s.q, s.v, s.a);
    const MatX<double> dtau_dq = data.dtau_dq, dtau_dv = data.dtau_dv, M = data.M;
    EXPECT_LE(scaled_error(data.tau, tau, max_abs(tau)), kRounding) << "tau of rnea_derivatives";
    const auto id_q = [&](const VecX<double>& x) { return rnea(model(), data, x, s.v, s.a); };
    const auto id_v = [&](const VecX<double>& x) { return rnea(model(), data, s.q, x, s.a); };
    const auto id_a = [&](const VecX<double>& x) { return rnea(model(), data, s.q, s.v, x); };
    EXPECT_LE(scaled_error(dtau_dq, central_difference_jacobian(id_q, s.q), max_abs(dtau_dq)), kFiniteDifference)
        << "dtau_dq";
    EXPECT_LE(scaled_error(dtau_dv, central_difference_jacobian(id_v, s.v), max_abs(dtau_dv)), kFiniteDifference)
        << "dtau_dv";
    EXPECT_LE(scaled_error(M, central_difference_jacobian(id_a, s.a), max_abs(M)), kFiniteDifference) << "M";
    // the friction's own slope on the diagonal, written out: the difference to the model
    // without friction, whose derivatives are checked in dynamics_test
    Data plain(ms_->plain);
    rnea_derivatives(ms_->plain, plain, s.q, s.v, s.a);
    for (int j = 0; j < n(); ++j) {
      const double slope =
          ms_->f[j] > 0 ? ms_->f[j] / ms_->eps[j] / std::pow(std::cosh(s.v[j] / ms_->eps[j]), 2) : 0.0;
      EXPECT_NEAR(dtau_dv(j, j) - plain.dtau_dv(j, j), slope, kRounding * std::max(1.0, max_abs(dtau_dv)))
          << "joint " << j;
    }
  }
}

TEST_P(Friction, AbaInvertsRneaAndItsDerivativesMatchFiniteDifferences) {
  Data data(model());
  for (const State& s : states()) {
    // rnea(aba(τ)) = τ and aba(rnea(a)) = a: friction enters both in the same place
    const VecX<double> qdd = aba(model(), data, s.q, s.v, s.tau);
    const VecX<double> tau = rnea(model(), data, s.q, s.v, qdd);
    const double scale = max_abs(crba(model(), data, s.q)) * max_abs(qdd);
    EXPECT_LE(scaled_error(tau, s.tau, scale), kRounding) << "rnea(aba(tau))";
    const VecX<double> tau_a = rnea(model(), data, s.q, s.v, s.a);
    const VecX<double> a = aba(model(), data, s.q, s.v, tau_a);
    const VecX<double> tau_back = rnea(model(), data, s.q, s.v, a);
    EXPECT_LE(scaled_error(tau_back, tau_a, std::max(scale, max_abs(tau_a))), kRounding) << "aba(rnea(a))";

    aba_derivatives(model(), data, s.q, s.v, s.tau);
    const MatX<double> da_dq = data.da_dq, da_dv = data.da_dv, Minv = data.Minv;
    const auto fd_q = [&](const VecX<double>& x) { return aba(model(), data, x, s.v, s.tau); };
    const auto fd_v = [&](const VecX<double>& x) { return aba(model(), data, s.q, x, s.tau); };
    const auto fd_u = [&](const VecX<double>& x) { return aba(model(), data, s.q, s.v, x); };
    EXPECT_LE(scaled_error(da_dq, central_difference_jacobian(fd_q, s.q), max_abs(da_dq)), kFiniteDifference)
        << "da_dq";
    EXPECT_LE(scaled_error(da_dv, central_difference_jacobian(fd_v, s.v), max_abs(da_dv)), kFiniteDifference)
        << "da_dv";
    EXPECT_LE(scaled_error(Minv, central_difference_jacobian(fd_u, s.tau), max_abs(Minv)), kFiniteDifference)
        << "da_dtau";
  }
}

TEST_P(Friction, RneaVjpIsTransposedDerivativesTimesW) {
  Data data(model());
  std::mt19937 rng(GetParam().seed + 7);
  for (const State& s : states()) {
    rnea_derivatives(model(), data, s.q, s.v, s.a);
    const MatX<double> dtau_dq = data.dtau_dq, dtau_dv = data.dtau_dv, M = data.M;
    rnea(model(), data, s.q, s.v, s.a);
    for (const VecX<double>& w : {test::random_vector(rng, n(), 1.0), test::random_vector(rng, n(), 10.0)}) {
      rnea_vjp(model(), data, w);
      const double wn = max_abs(w);
      EXPECT_LE(scaled_error(data.g_q, dtau_dq.transpose() * w, max_abs(dtau_dq) * wn), kRounding) << "g_q";
      EXPECT_LE(scaled_error(data.g_v, dtau_dv.transpose() * w, max_abs(dtau_dv) * wn), kRounding) << "g_v";
      EXPECT_LE(scaled_error(data.g_a, M * w, max_abs(M) * wn), kRounding) << "g_a";
    }
    // and after aba, from the kinematics it leaves (rnea_after_aba): the same products
    Data ref(model());
    const VecX<double> qdd = aba(model(), data, s.q, s.v, s.tau);
    rnea_after_aba(model(), data, s.q, s.v);
    rnea(model(), ref, s.q, s.v, qdd);
    const VecX<double> w = test::random_vector(rng, n(), 1.0);
    rnea_vjp(model(), data, w);
    rnea_vjp(model(), ref, w);
    EXPECT_LE(scaled_error(data.g_v, ref.g_v, max_abs(ref.g_v)), kRounding) << "g_v after aba";
  }
}

// kStageLanes different states in the lanes of one pack (the states of this case, then more):
// every lane equals the double kernel at its own state
TEST_P(Friction, PackLanesEqualTheDoubleKernels) {
  static_assert(kStates <= kStageLanes);
  const int n = this->n();
  std::vector<State> ss = states();
  std::mt19937 rng(GetParam().seed + 11);
  while (static_cast<int>(ss.size()) < kStageLanes) ss.push_back(random_state(*ms_, rng, static_cast<int>(ss.size())));
  std::vector<VecX<double>> ws;
  for (int k = 0; k < kStageLanes; ++k) ws.push_back(test::random_vector(rng, n, 2.0));
  const auto member = [&](VecX<double> State::*x) {
    std::vector<VecX<double>> out;
    for (const State& s : ss) out.push_back(s.*x);
    return test::packed(out);
  };
  const VecX<StagePack> q = member(&State::q), v = member(&State::v), a = member(&State::a),
                        tau = member(&State::tau), w = test::packed(ws);
  const auto rel = [](const MatX<double>& x, const MatX<double>& y) {
    return (x - y).cwiseAbs().maxCoeff() / std::max(1.0, y.cwiseAbs().maxCoeff());
  };

  DataTpl<StagePack> pd(model());
  Data d(model());
  // rnea and its adjoint
  rnea(model(), pd, q, v, a);
  rnea_vjp(model(), pd, w);
  for (int k = 0; k < kStageLanes; ++k) {
    SCOPED_TRACE("lane " + std::to_string(k));
    const State& s = ss[static_cast<size_t>(k)];
    rnea(model(), d, s.q, s.v, s.a);
    EXPECT_LE(rel(test::lane(pd.tau, k), d.tau), kLanes) << "rnea";
    rnea_vjp(model(), d, ws[static_cast<size_t>(k)]);
    EXPECT_LE(rel(test::lane(pd.g_q, k), d.g_q), kLanes) << "g_q";
    EXPECT_LE(rel(test::lane(pd.g_v, k), d.g_v), kLanes) << "g_v";
    EXPECT_LE(rel(test::lane(pd.g_a, k), d.g_a), kLanes) << "g_a";
  }
  // rnea derivatives
  rnea_derivatives(model(), pd, q, v, a);
  for (int k = 0; k < kStageLanes; ++k) {
    SCOPED_TRACE("lane " + std::to_string(k));
    const State& s = ss[static_cast<size_t>(k)];
    rnea_derivatives(model(), d, s.q, s.v, s.a);
    EXPECT_LE(rel(test::lane(pd.tau, k), d.tau), kLanes) << "tau of rnea_derivatives";
    EXPECT_LE(rel(test::lane(pd.dtau_dq, k), d.dtau_dq), kLanes) << "dtau_dq";
    EXPECT_LE(rel(test::lane(pd.dtau_dv, k), d.dtau_dv), kLanes) << "dtau_dv";
    EXPECT_LE(rel(test::lane(pd.M, k), d.M), kLanes) << "M";
  }
  // aba, its derivatives, and rnea at its result
  aba(model(), pd, q, v, tau);
  const VecX<StagePack> qdd = pd.qdd;
  aba_derivatives_after_aba(model(), pd, q, v);
  for (int k = 0; k < kStageLanes; ++k) {
    SCOPED_TRACE("lane " + std::to_string(k));
    const State& s = ss[static_cast<size_t>(k)];
    aba_derivatives(model(), d, s.q, s.v, s.tau);
    EXPECT_LE(rel(test::lane(qdd, k), d.qdd), kLanes) << "aba";
    EXPECT_LE(rel(test::lane(pd.da_dq, k), d.da_dq), kLanes) << "da_dq";
    EXPECT_LE(rel(test::lane(pd.da_dv, k), d.da_dv), kLanes) << "da_dv";
    EXPECT_LE(rel(test::lane(pd.Minv, k), d.Minv), kLanes) << "Minv";
  }
  aba(model(), pd, q, v, tau);
  rnea_after_aba(model(), pd, q, v);
  for (int k = 0; k < kStageLanes; ++k) {
    const State& s = ss[static_cast<size_t>(k)];
    aba(model(), d, s.q, s.v, s.tau);
    EXPECT_LE(rel(test::lane(pd.tau, k), rnea_after_aba(model(), d, s.q, s.v)), kLanes) << "rnea_after_aba, lane " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, Friction, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.label; });

// ---------------------------------------------------------------------------------------------
// with_joint_friction's argument checks

TEST(WithJointFriction, RefusesNegativeZeroVelocityNonFiniteAndWrongSizes) {
  const test::Problem p = test::load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml");
  const Model& model = p.model;
  const int n = model.n;
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const VecX<double> f = VecX<double>::Constant(n, 0.5), eps = VecX<double>::Constant(n, 0.1);
  EXPECT_NO_THROW(with_joint_friction(model, f, eps));
  // no friction needs no smoothing velocity
  EXPECT_NO_THROW(with_joint_friction(model, VecX<double>::Zero(n), VecX<double>::Zero(n)));

  struct Bad {
    const char* what;
    int joint;
    double f, eps;
  };
  for (const Bad& b : {Bad{"f < 0", 2, -0.1, 0.1}, Bad{"f > 0 with eps = 0", 1, 0.5, 0.0},
                       Bad{"f > 0 with eps < 0", 3, 0.5, -0.1}, Bad{"f NaN", 0, nan, 0.1},
                       Bad{"f inf", 2, inf, 0.1}, Bad{"eps NaN", 1, 0.5, nan}, Bad{"eps inf", 3, 0.5, inf},
                       Bad{"eps NaN without friction", 0, 0.0, nan}}) {
    SCOPED_TRACE(b.what);
    VecX<double> fb = f, eb = eps;
    fb[b.joint] = b.f;
    eb[b.joint] = b.eps;
    try {
      with_joint_friction(model, fb, eb);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("link " + std::to_string(b.joint)), std::string::npos)
          << "the message must name the joint: " << e.what();
    }
  }
  for (const int size : {0, n - 1, n + 1}) {
    SCOPED_TRACE("size " + std::to_string(size));
    EXPECT_THROW(with_joint_friction(model, VecX<double>::Constant(size, 0.5), eps), std::invalid_argument);
    EXPECT_THROW(with_joint_friction(model, f, VecX<double>::Constant(size, 0.1)), std::invalid_argument);
  }
}

}  // namespace
}  // namespace idmpc
