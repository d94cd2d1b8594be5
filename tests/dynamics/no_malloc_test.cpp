// The dynamics algorithms allocate no heap memory once Data exists (STYLE.md, Model / Data).
//
// Eigen checks every heap allocation against a runtime flag when EIGEN_RUNTIME_NO_MALLOC is
// defined, through eigen_assert; NDEBUG is undefined so that asserts stay on in Release, and
// eigen_assert throws so that a forbidden allocation fails the test instead of aborting the
// binary. Both must come before any Eigen include. The algorithms are templates, so the
// instantiations this file makes carry the check.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC
#include <stdexcept>
#define eigen_assert(x) \
  do { \
    if (!(x)) throw std::logic_error("Eigen assertion failed: " #x); \
  } while (false)

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/spatial/pack.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc {
namespace {

/// forbids Eigen heap allocations for its lifetime (re-allowed even if a check throws)
class NoMalloc {
 public:
  NoMalloc() { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoMalloc() { Eigen::internal::set_is_malloc_allowed(true); }
  NoMalloc(const NoMalloc&) = delete;
  NoMalloc& operator=(const NoMalloc&) = delete;
};

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

TEST(NoMallocGuard, IsArmed) {
  // the guard must catch an allocation, or the tests below prove nothing
  NoMalloc guard;
  EXPECT_THROW(VecX<double> tmp(5), std::logic_error);
}

class NoMallocTest : public ::testing::TestWithParam<std::string> {
 protected:
  void TearDown() override {
    const std::vector<std::string> warnings = mj::take_warnings();
    EXPECT_TRUE(warnings.empty()) << "MuJoCo warnings:" << joined(warnings);
  }
};

TEST_P(NoMallocTest, AlgorithmsDoNotAllocateAfterDataConstruction) {
  const std::string path = std::string(IDMPC_SOURCE_DIR) + "/mjcf/" + GetParam() + ".xml";
  const mj::ModelPtr m = mj::load_model(path);
  const Model model = mj::import_model(m.get(), path).model;
  const int n = model.n;

  // everything allocated up front: workspace and inputs
  Data data(model);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  VecX<double> q(n), v(n), a(n), tau(n), w(n), x(n);
  for (VecX<double>* y : {&q, &v, &a, &tau, &w, &x}) {
    for (int i = 0; i < n; ++i) (*y)[i] = unit(rng);
  }
  q += model.q_ref;

  // each algorithm under its own guard, so a failure names it
  const auto guarded = [](const char* algorithm, const auto& call) {
    try {
      NoMalloc guard;
      call();
    } catch (const std::logic_error& e) {
      ADD_FAILURE() << algorithm << " allocated on the heap: " << e.what();
    }
  };
  guarded("rnea", [&] { rnea(model, data, q, v, a); });
  guarded("rnea_vjp", [&] { rnea_vjp(model, data, w); });
  guarded("aba", [&] { aba(model, data, q, v, tau); });
  guarded("minv_apply", [&] { minv_apply(model, data, x); });
  guarded("rnea_after_aba", [&] { rnea_after_aba(model, data, q, v); });
  guarded("crba", [&] { crba(model, data, q); });
  guarded("ltdl_factor", [&] { ltdl_factor(model, data); });
  guarded("ltdl_solve", [&] { ltdl_solve(model, data, x); });
  guarded("minv_matrix", [&] { minv_matrix(model, data, q); });
  guarded("rnea_derivatives", [&] { rnea_derivatives(model, data, q, v, a); });
  guarded("aba_derivatives", [&] { aba_derivatives(model, data, q, v, tau); });
  // frame kinematics of a point on the last link, in doubles and in SIMD lanes
  Frame frame{"tool", n - 1, {}};
  frame.placement.r = Vec3<double>(0.1, 0.2, 0.3);
  FrameKinematics<double> fk(model, frame);
  FrameKinematics<StagePack> fk_lanes(model, frame);
  FrameKinematics<double>::Jacobian J(6, n);
  FrameKinematics<StagePack>::Jacobian J_lanes(6, n);
  const VecX<StagePack> q_lanes = q.cast<StagePack>();
  VecX<StagePack> g_lanes = VecX<StagePack>::Constant(n, StagePack(0.0));
  const Vec3<double> f(1, 2, 3);
  const Vec3<StagePack> f_lanes = f.cast<StagePack>();
  guarded("FrameKinematics::compute", [&] { fk.compute(model, q); });
  guarded("FrameKinematics::jacobian", [&] { fk.jacobian(J); });
  guarded("FrameKinematics::add_jacobian_transpose_times", [&] { fk.add_jacobian_transpose_times(f, f, x); });
  guarded("FrameKinematics<StagePack>::compute", [&] { fk_lanes.compute(model, q_lanes); });
  guarded("FrameKinematics<StagePack>::jacobian", [&] { fk_lanes.jacobian(J_lanes); });
  guarded("FrameKinematics<StagePack>::add_jacobian_transpose_times",
          [&] { fk_lanes.add_jacobian_transpose_times(f_lanes, f_lanes, g_lanes); });
  EXPECT_GT(J.norm(), 0.0);
  // the guarded calls did real work
  EXPECT_TRUE(data.tau.allFinite() && data.qdd.allFinite() && data.Minv.allFinite() &&
              data.y_ltdl.allFinite());
  EXPECT_GT(data.M.norm(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Models, NoMallocTest, ::testing::Values("arm4", "tree", "chain32"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
}  // namespace idmpc
