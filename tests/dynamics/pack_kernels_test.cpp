// The SIMD-pack instantiation of every dynamics kernel against its double instantiation, lane by
// lane: each of the kStageLanes lanes holds its own random point (q, v, a, τ, w, x), the pack
// kernel runs once, and every output lane must equal the double kernel at that lane's point.
// Kernels: rnea, rnea_vjp, rnea_derivatives (τ, ∂τ/∂q, ∂τ/∂v, M), crba, ltdl_factor and
// ltdl_solve, aba, minv_apply, rnea_after_aba, minv_apply_columns, minv_matrix_after_aba,
// minv_matrix, aba_derivatives_after_aba and aba_derivatives. Models: every shipped model, seeded
// random trees (some with axis-aligned joints, the joint kernels' fast paths) and random trees
// with joint friction (the tanh terms). FrameKinematics's pack path has the same check in
// kinematics_test.cpp (PackLanesEqualTheDoublePath).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/pack.hpp"
#include "support/lanes.hpp"
#include "support/problems.hpp"
#include "support/random_model.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

using P = StagePack;
constexpr int kW = kStageLanes;
// the lanes run the double kernels' operations; only the order of Eigen's reductions and
// products and the compiler's contraction into fused multiply-adds differ. Relative to
// max(1, |double result|)
constexpr double kLanes = 1e-12;
// minv_matrix accumulates the articulated inertias in the world frame, where they are O(m·r²)
// and cancel down to M⁻¹'s pivots: its result rounds as M⁻¹·ΔY·M⁻¹ with |ΔY| ~ ε|oYA|, so its
// lanes are compared in the scale |oYA|·|M⁻¹|² (measured: at most 1e-16 of it, over all
// models; against max(1, |M⁻¹|) up to 5e-13 on mjcf/tree.xml, whose M⁻¹ reaches 2e3, where the
// double path itself differs as much from minv_matrix_after_aba, the same M⁻¹ from link-frame
// inertias)
constexpr double kInverseRounding = 1e-14;
constexpr int kRandomTrees = 6;
constexpr int kAlignedTrees = 2;
constexpr int kFrictionTrees = 2;
constexpr int kGravcompTrees = 6;  // random trees with gravity compensation on some bodies

struct Case {
  std::string label;
  Model model;
};

// every shipped model, random trees, random trees with axis-aligned joints and with friction
const std::vector<Case>& cases() {
  static const std::vector<Case> out = [] {
    std::vector<Case> c;
    for (const std::string& path : test::shipped_model_paths()) {
      const std::string stem = std::filesystem::path(path).stem().string();
      c.push_back({stem, test::load_problem(path).model});  // a gripper's held joints welded
    }
    const auto tree = [&](const std::string& label, unsigned seed, bool aligned, bool gravcomp = false) {
      test::RandomTreeOptions options;
      options.aligned_axes = aligned;
      options.gravcomp = gravcomp;
      const mj::ModelPtr m = mj::load_model_from_string(test::random_tree_mjcf(seed, options));
      return mj::import_model(m.get(), label).model;
    };
    for (unsigned s = 1; s <= kRandomTrees; ++s) {
      const std::string label = "random_tree_seed" + std::to_string(s);
      c.push_back({label, tree(label, s, false)});
    }
    for (unsigned s = 1; s <= kAlignedTrees; ++s) {
      const std::string label = "aligned_tree_seed" + std::to_string(s);
      c.push_back({label, tree(label, s, true)});
    }
    for (unsigned s = 1; s <= kGravcompTrees; ++s) {
      const std::string label = "gravcomp_tree_seed" + std::to_string(s);
      c.push_back({label, tree(label, s, false, true)});
    }
    for (unsigned s = 1; s <= kFrictionTrees; ++s) {
      const std::string label = "friction_tree_seed" + std::to_string(s);
      const Model plain = tree(label, 100 + s, false);
      std::mt19937 rng(s);
      // f in [0.1, 2], ε in [0.05, 0.5]: the lanes' velocities cover tanh's slope and saturation
      const VecX<double> f = test::random_vector(rng, plain.n, 0.1, 2.0);
      const VecX<double> eps = test::random_vector(rng, plain.n, 0.05, 0.5);
      c.push_back({label, with_joint_friction(plain, f, eps)});
    }
    return c;
  }();
  return out;
}

/// kW random points, one per lane, as doubles and packed
struct Points {
  std::vector<VecX<double>> q, v, a, tau, w, x;
  std::vector<MatX<double>> rhs;  // right-hand sides of minv_apply_columns (n × m)
  VecX<P> qp, vp, ap, taup, wp, xp;
  MatX<P> rhsp;
};

Points random_points(const Model& model, unsigned seed, int m) {
  std::mt19937 rng(seed);
  const int n = model.n;
  Points p;
  for (int k = 0; k < kW; ++k) {
    p.q.push_back(model.q_ref + test::random_vector(rng, n, 3.0));
    p.v.push_back(test::random_vector(rng, n, 2.0));
    p.a.push_back(test::random_vector(rng, n, 5.0));
    p.tau.push_back(test::random_vector(rng, n, 5.0));
    p.w.push_back(test::random_vector(rng, n, 2.0));
    p.x.push_back(test::random_vector(rng, n, 2.0));
    MatX<double> r(n, m);
    for (int j = 0; j < m; ++j) r.col(j) = test::random_vector(rng, n, 2.0);
    p.rhs.push_back(r);
  }
  p.qp = test::packed(p.q);
  p.vp = test::packed(p.v);
  p.ap = test::packed(p.a);
  p.taup = test::packed(p.tau);
  p.wp = test::packed(p.w);
  p.xp = test::packed(p.x);
  p.rhsp.resize(n, m);
  for (int j = 0; j < m; ++j) {
    std::vector<VecX<double>> col;
    for (int k = 0; k < kW; ++k) col.push_back(p.rhs[static_cast<size_t>(k)].col(j));
    p.rhsp.col(j) = test::packed(col);
  }
  return p;
}

/// the worst lane error of each output over all models, printed at the end of each test
class Worst {
 public:
  explicit Worst(const char* kernel) : kernel_(kernel) {}
  ~Worst() {
    std::printf("[ measured ] %s, worst scaled lane error per output:\n", kernel_);
    for (const auto& [what, e] : worst_) {
      std::printf("    %s: %.2g (tolerance %g, %s)\n", what.c_str(), e.error, e.tolerance, e.model.c_str());
    }
  }
  /// expects lane k of `pack` to equal `expected`
  /// expects lane k of `pack` to equal `expected` within `tolerance` of `scale` (by default
  /// kLanes of max(1, |expected|))
  template <typename X>
  void expect(const std::string& what, const Eigen::DenseBase<X>& pack, int k, const MatX<double>& expected,
              const std::string& model, double scale = 0, double tolerance = kLanes) {
    const MatX<double> got = test::lane(pack, k);
    ASSERT_EQ(got.rows(), expected.rows()) << what;
    ASSERT_EQ(got.cols(), expected.cols()) << what;
    if (expected.size() == 0) return;
    if (scale == 0) scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
    const double e = (got - expected).cwiseAbs().maxCoeff() / scale;
    auto [it, inserted] = worst_.try_emplace(what, Entry{e, tolerance, model});
    if (!inserted && e > it->second.error) it->second = {e, tolerance, model};
    EXPECT_LE(e, tolerance) << what << " of lane " << k << " (scaled error " << e << ")\nlane:\n"
                            << got << "\ndouble kernel:\n"
                            << expected;
  }

 private:
  struct Entry {
    double error, tolerance;
    std::string model;
  };
  const char* kernel_;
  std::map<std::string, Entry> worst_;
};

// calls f(case, points, pack data, double data) for every model, with its own seed
template <typename F> void for_each_model(unsigned seed, F&& f) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.label + " (n = " + std::to_string(c.model.n) + ")");
    const Points p = random_points(c.model, seed++, std::max(1, c.model.n / 2));
    DataTpl<P> pd(c.model);
    Data d(c.model);
    f(c, p, pd, d);
  }
}

TEST(PackKernels, RneaAndItsVjp) {
  Worst worst("rnea, rnea_vjp");
  for_each_model(1, [&](const Case& c, const Points& p, DataTpl<P>& pd, Data& d) {
    rnea(c.model, pd, p.qp, p.vp, p.ap);
    rnea_vjp(c.model, pd, p.wp);
    for (int k = 0; k < kW; ++k) {
      rnea(c.model, d, p.q[k], p.v[k], p.a[k]);
      worst.expect("rnea tau", pd.tau, k, d.tau, c.label);
      rnea_vjp(c.model, d, p.w[k]);
      worst.expect("rnea_vjp g_q", pd.g_q, k, d.g_q, c.label);
      worst.expect("rnea_vjp g_v", pd.g_v, k, d.g_v, c.label);
      worst.expect("rnea_vjp g_a", pd.g_a, k, d.g_a, c.label);
    }
  });
}

TEST(PackKernels, RneaDerivatives) {
  Worst worst("rnea_derivatives");
  for_each_model(101, [&](const Case& c, const Points& p, DataTpl<P>& pd, Data& d) {
    rnea_derivatives(c.model, pd, p.qp, p.vp, p.ap);
    for (int k = 0; k < kW; ++k) {
      rnea_derivatives(c.model, d, p.q[k], p.v[k], p.a[k]);
      worst.expect("tau", pd.tau, k, d.tau, c.label);
      worst.expect("dtau_dq", pd.dtau_dq, k, d.dtau_dq, c.label);
      worst.expect("dtau_dv", pd.dtau_dv, k, d.dtau_dv, c.label);
      worst.expect("M", pd.M, k, d.M, c.label);
    }
  });
}

TEST(PackKernels, CrbaAndLtdl) {
  Worst worst("crba, ltdl_factor, ltdl_solve");
  for_each_model(201, [&](const Case& c, const Points& p, DataTpl<P>& pd, Data& d) {
    crba(c.model, pd, p.qp);
    const MatX<P> M = pd.M;
    ltdl_factor(c.model, pd);
    ltdl_solve(c.model, pd, p.xp);
    for (int k = 0; k < kW; ++k) {
      crba(c.model, d, p.q[k]);
      worst.expect("crba M", M, k, d.M, c.label);
      ltdl_factor(c.model, d);
      worst.expect("ltdl Lt", pd.Lt, k, d.Lt, c.label);
      worst.expect("ltdl Dl", pd.Dl, k, d.Dl, c.label);
      worst.expect("ltdl Dlinv", pd.Dlinv, k, d.Dlinv, c.label);
      worst.expect("ltdl_solve", pd.y_ltdl, k, ltdl_solve(c.model, d, p.x[k]), c.label);
    }
  });
}

// aba, then what reuses its factorization: minv_apply, rnea_after_aba, minv_apply_columns,
// minv_matrix_after_aba; and minv_matrix from q alone
TEST(PackKernels, AbaAndTheInverseMassMatrix) {
  Worst worst("aba, minv_apply, rnea_after_aba, minv_apply_columns, minv_matrix(_after_aba)");
  for_each_model(301, [&](const Case& c, const Points& p, DataTpl<P>& pd, Data& d) {
    const int m = static_cast<int>(p.rhsp.cols());
    aba(c.model, pd, p.qp, p.vp, p.taup);
    const VecX<P> qdd = pd.qdd;
    const VecX<P> minv_x = minv_apply(c.model, pd, p.xp);
    const VecX<P> tau = rnea_after_aba(c.model, pd, p.qp, p.vp);
    pd.rhs.leftCols(m) = p.rhsp;
    minv_apply_columns(c.model, pd, m);
    const MatX<P> minv_after_aba = minv_matrix_after_aba(c.model, pd);
    minv_matrix(c.model, pd, p.qp);
    for (int k = 0; k < kW; ++k) {
      aba(c.model, d, p.q[k], p.v[k], p.tau[k]);
      worst.expect("aba qdd", qdd, k, d.qdd, c.label);
      worst.expect("minv_apply", minv_x, k, minv_apply(c.model, d, p.x[k]), c.label);
      worst.expect("rnea_after_aba tau", tau, k, rnea_after_aba(c.model, d, p.q[k], p.v[k]), c.label);
      d.rhs.leftCols(m) = p.rhs[static_cast<size_t>(k)];
      minv_apply_columns(c.model, d, m);
      worst.expect("minv_apply_columns", pd.rhs.leftCols(m), k, d.rhs.leftCols(m), c.label);
      worst.expect("minv_matrix_after_aba", minv_after_aba, k, minv_matrix_after_aba(c.model, d), c.label);
      const MatX<double> minv = minv_matrix(c.model, d, p.q[k]);
      double world_inertia = 1.0;
      for (const Mat6<double>& Y : d.oYA) world_inertia = std::max(world_inertia, Y.cwiseAbs().maxCoeff());
      const double minv_scale = std::max(1.0, minv.cwiseAbs().maxCoeff());
      worst.expect("minv_matrix", pd.Minv, k, minv, c.label, world_inertia * minv_scale * minv_scale,
                   kInverseRounding);
    }
  });
}

TEST(PackKernels, AbaDerivatives) {
  Worst worst("aba_derivatives(_after_aba)");
  for_each_model(401, [&](const Case& c, const Points& p, DataTpl<P>& pd, Data& d) {
    // after aba (the OCP's path), then the whole algorithm at the same points into a second
    // workspace
    aba(c.model, pd, p.qp, p.vp, p.taup);
    aba_derivatives_after_aba(c.model, pd, p.qp, p.vp);
    DataTpl<P> pd_full(c.model);
    aba_derivatives(c.model, pd_full, p.qp, p.vp, p.taup);
    for (int k = 0; k < kW; ++k) {
      aba_derivatives(c.model, d, p.q[k], p.v[k], p.tau[k]);
      for (const auto& [variant, data] : {std::pair<const char*, DataTpl<P>*>{"after aba", &pd},
                                          std::pair<const char*, DataTpl<P>*>{"whole", &pd_full}}) {
        const std::string v = std::string(" (") + variant + ")";
        worst.expect("qdd" + v, data->qdd, k, d.qdd, c.label);
        worst.expect("da_dq" + v, data->da_dq, k, d.da_dq, c.label);
        worst.expect("da_dv" + v, data->da_dv, k, d.da_dv, c.label);
        worst.expect("Minv" + v, data->Minv, k, d.Minv, c.label);
      }
    }
  });
}

}  // namespace
}  // namespace idmpc
