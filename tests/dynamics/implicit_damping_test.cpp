// with_implicit_damping: the horizon model for heavily damped arms. Its forward dynamics make
// explicit Euler integrate the damping at the end of the step,
//   M (v⁺ − v)/dt = τ − c − D v⁺,   v⁺ = v + dt·FD'(q, v, τ),
// checked against the plant model's own inverse dynamics (which hold −D v): ID(q, v, a) − D v
// + D v⁺ = τ, i.e. ID(q, v, a) + dt·D a = τ.
#include <gtest/gtest.h>

#include <random>

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/rnea.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

TEST(ImplicitDamping, EulerStepHoldsTheDampingAtTheEndOfTheStep) {
  const test::Problem p = test::load_problem(IDMPC_SOURCE_DIR "/mjcf/tree.xml");  // damped joints
  const Model& model = p.model;
  ASSERT_GT(model.damping.maxCoeff(), 0.0);
  const double dt = 0.04;
  const Model implicit = with_implicit_damping(model, dt);
  EXPECT_EQ(implicit.armature, model.armature + dt * model.damping);
  EXPECT_EQ(implicit.damping, model.damping);

  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Data d(model), di(implicit);
  for (int k = 0; k < 5; ++k) {
    VecX<double> q(model.n), v(model.n), tau(model.n);
    for (int j = 0; j < model.n; ++j) {
      q[j] = u(rng);
      v[j] = 3 * u(rng);
      tau[j] = 5 * u(rng);
    }
    const VecX<double> a = aba(implicit, di, q, v, tau);
    const VecX<double> back = rnea(model, d, q, v, a) + dt * model.damping.cwiseProduct(a);
    EXPECT_LE((back - tau).cwiseAbs().maxCoeff(), 1e-10 * (1 + tau.cwiseAbs().maxCoeff()));
    // and the explicit model does not: the damping is taken at the start of the step
    const VecX<double> a_explicit = aba(model, d, q, v, tau);
    EXPECT_GT((a_explicit - a).cwiseAbs().maxCoeff(), 1e-3);
  }
  EXPECT_THROW(with_implicit_damping(model, -1), std::invalid_argument);
}

}  // namespace
}  // namespace idmpc
