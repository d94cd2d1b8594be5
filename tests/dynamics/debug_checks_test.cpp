// The checks of the dynamics entry points. The call-order preconditions (rnea_vjp after rnea;
// minv_apply, minv_apply_columns, aba_derivatives_after_aba after aba, at the same point;
// ltdl_factor after M, ltdl_solve after ltdl_factor) are debug checks: death tests, run where the
// checks are compiled in (IDMPC_DEBUG_CHECKS: the sanitizer build), skipped in Release. Sizes and
// the parts a Data was made with are checked in every build: they throw.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {
namespace {

/// a branching tree of three links, built without MuJoCo
Model small_tree() {
  std::vector<Link> links(3);
  for (int i = 0; i < 3; ++i) {
    links[i].I = Inertia<double>::from_com(1.0, Vec3<double>(0.1, 0, 0), Mat3<double>::Identity());
    links[i].X_tree.r = Vec3<double>(0.5, 0, 0);
  }
  links[1].parent = 0;
  links[2].parent = 0;
  links[2].joint_type = JointType::kPrismatic;
  return Model(links, Vec3<double>(0, 0, -9.81), "small tree");
}

class DebugChecksDeathTest : public ::testing::Test {
 protected:
  void SetUp() override {
#if !IDMPC_DEBUG_CHECKS
    GTEST_SKIP() << "debug checks are compiled out in this build (NDEBUG)";
#endif
    GTEST_FLAG_SET(death_test_style, "threadsafe");
  }
  const Model model_ = small_tree();
  Data data_{model_};
  const VecX<double> q_ = VecX<double>::Constant(3, 0.3), v_ = VecX<double>::Constant(3, -0.2),
                     a_ = VecX<double>::Constant(3, 0.7), x_ = VecX<double>::Constant(3, 1.0);
};

TEST_F(DebugChecksDeathTest, RneaVjpWithoutRneaAborts) {
  EXPECT_DEATH(rnea_vjp(model_, data_, x_), "rnea_vjp needs rnea");
}

TEST_F(DebugChecksDeathTest, RneaVjpAfterAbaOrKinematicsElsewhereAborts) {
  rnea(model_, data_, q_, v_, a_);
  rnea_vjp(model_, data_, x_);  // fine
  crba(model_, data_, q_);       // same q: rnea's pass still valid
  rnea_vjp(model_, data_, x_);
  crba(model_, data_, v_);       // kinematics at another q
  EXPECT_DEATH(rnea_vjp(model_, data_, x_), "rnea_vjp needs rnea");
  rnea(model_, data_, q_, v_, a_);
  aba(model_, data_, q_, v_, a_);  // overwrites rnea's velocities and accelerations
  EXPECT_DEATH(rnea_vjp(model_, data_, x_), "rnea_vjp needs rnea");
}

TEST_F(DebugChecksDeathTest, AbaFactorizationUsersWithoutAbaAbort) {
  EXPECT_DEATH(minv_apply(model_, data_, x_), "minv_apply needs aba");
  EXPECT_DEATH(minv_apply_columns(model_, data_, 3), "minv_apply_columns needs aba");
  EXPECT_DEATH(aba_derivatives_after_aba(model_, data_, q_, v_), "aba_derivatives_after_aba needs aba");
}

TEST_F(DebugChecksDeathTest, AbaFactorizationUsersAtAnotherPointAbort) {
  aba(model_, data_, q_, v_, a_);
  minv_apply(model_, data_, x_);                // fine
  rnea(model_, data_, q_, v_, a_);              // same q, as the FD costate sweep does
  minv_apply(model_, data_, x_);
  EXPECT_DEATH(aba_derivatives_after_aba(model_, data_, q_, a_), "at this \\(q, v\\)");
  aba_derivatives_after_aba(model_, data_, q_, v_);  // fine
  rnea(model_, data_, v_, v_, a_);              // kinematics at another q
  EXPECT_DEATH(minv_apply(model_, data_, x_), "minv_apply needs aba");
  EXPECT_DEATH(minv_apply_columns(model_, data_, 3), "minv_apply_columns needs aba");
}

TEST_F(DebugChecksDeathTest, LtdlWithoutMassMatrixOrFactorAborts) {
  aba(model_, data_, q_, v_, a_);  // no M yet
  EXPECT_DEATH(ltdl_factor(model_, data_), "ltdl_factor needs data.M");
  EXPECT_DEATH(ltdl_solve(model_, data_, x_), "ltdl_solve needs ltdl_factor");
  crba(model_, data_, q_);
  EXPECT_DEATH(ltdl_solve(model_, data_, x_), "ltdl_solve needs ltdl_factor");
  ltdl_factor(model_, data_);
  ltdl_solve(model_, data_, x_);  // fine
  Data fresh(model_);
  rnea_derivatives(model_, fresh, q_, v_, a_);  // M as ∂τ/∂a
  ltdl_factor(model_, fresh);                   // fine
}

// sizes and the parts a Data was made with are checked in every build (std::invalid_argument)
class ArgumentChecks : public DebugChecksDeathTest {
 protected:
  void SetUp() override {}
};

TEST_F(ArgumentChecks, WrongSizesThrowInEveryBuild) {
  const VecX<double> short_ = VecX<double>::Zero(2);
  auto throws = [](auto&& call, const std::string& message) {
    try {
      call();
      ADD_FAILURE() << "expected std::invalid_argument: " << message;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  throws([&] { rnea(model_, data_, short_, v_, a_); }, "rnea: q, v, a must have size model.n");
  throws([&] { aba(model_, data_, q_, v_, short_); }, "aba: q, v, tau must have size model.n");
  throws([&] { crba(model_, data_, short_); }, "crba: q must have size model.n");
  throws([&] { rnea_derivatives(model_, data_, q_, short_, a_); }, "rnea_derivatives: q, v, a");
  rnea(model_, data_, q_, v_, a_);
  throws([&] { rnea_vjp(model_, data_, short_); }, "rnea_vjp: w must have size model.n");
  aba(model_, data_, q_, v_, a_);
  throws([&] { minv_apply(model_, data_, short_); }, "minv_apply: x must have size model.n");
  throws([&] { minv_apply_columns(model_, data_, 4); }, "expected 0 <= m <= model.n");
  crba(model_, data_, q_);
  ltdl_factor(model_, data_);
  throws([&] { ltdl_solve(model_, data_, short_); }, "ltdl_solve: x must have size model.n");
  const Model other(std::vector<Link>(2), Vec3<double>::Zero());
  throws([&] { rnea(other, data_, short_, short_, short_); }, "data was made for a model of another size");
  Data rnea_only(model_, DataParts::rnea());
  throws([&] { aba(model_, rnea_only, q_, v_, a_); }, "aba: data was made without its rnea and aba parts");
}

}  // namespace
}  // namespace idmpc
