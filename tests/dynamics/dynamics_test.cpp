// Our dynamics against MuJoCo (check_model) on every shipped model, on 200 seeded random
// trees and on 25 with axis-aligned joints (the joint kernels' fast paths, both signs), plus the internal-consistency identities written out directly: CRBA = RNEA columns
// minus bias, M symmetric positive definite, M·M⁻¹ = I, minv_apply = M⁻¹x, M = LᵀDL,
// rnea(aba(τ)) = τ, analytic derivatives vs central differences, adjoints vs matrices.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "support/problems.hpp"
#include "support/random_model.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

// identities that hold exactly in real arithmetic: rounding in O(n·depth) flops of O(1)-O(1e4)
// numbers, relative to the quantity's scale
constexpr double kRounding = 1e-10;
// inverting M loses up to cond(M)·ε; measured as ‖M·M⁻¹ − I‖ / (‖M‖·‖M⁻¹‖)
constexpr double kInverseRounding = 1e-13;
// central differences with h = ε^(1/3)·max(1,|x|): truncation h²·f'''/6 plus rounding ε·f/h
constexpr double kFiniteDifference = 1e-6;
constexpr int kRandomTrees = 200;
constexpr int kAlignedTrees = 25;  // random trees whose joint axes are all ±e_k
constexpr int kGravcompTrees = 40;  // random trees with gravity compensation on some bodies
constexpr int kShippedSeeds = 3;       // (model, seed) pairs per shipped model
constexpr int kSamplesShipped = 3;     // random states per (shipped model, seed)
constexpr int kSamplesRandomTree = 2;  // random states per random tree (keeps runtime low)

/// one (model, seed) pair: a shipped file, or a random tree drawn from the seed
struct Case {
  std::string label;  // test-name-safe: "<file stem>_seed<k>" or "random_tree_seed<k>"
  std::string path;   // empty for a random tree
  unsigned seed = 0;  // random tree seed (if any) and seed of the random states
  int samples = 0;
  bool aligned = false;  // random tree with axis-aligned joints (RandomTreeOptions::aligned_axes)
  bool gravcomp = false;  // random tree with gravity compensation (RandomTreeOptions::gravcomp)
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << c.label << (c.path.empty() ? " (random_tree_mjcf(" + std::to_string(c.seed) +
                                          (c.aligned ? ", aligned axes))" : c.gravcomp ? ", gravcomp))" : "))")
                                    : " (" + c.path + ", seed " + std::to_string(c.seed) + ")");
}

std::string sanitize(std::string s) {
  for (char& ch : s) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return s;
}

std::vector<Case> shipped_cases() {
  std::vector<Case> out;
  for (const std::string& path : test::shipped_model_paths()) {
    const std::string stem = sanitize(std::filesystem::path(path).stem().string());
    for (unsigned s = 1; s <= kShippedSeeds; ++s) {
      out.push_back({stem + "_seed" + std::to_string(s), path, s, kSamplesShipped});
    }
  }
  return out;
}

std::vector<Case> random_tree_cases() {
  std::vector<Case> out;
  for (unsigned s = 1; s <= kRandomTrees; ++s) {
    out.push_back({"random_tree_seed" + std::to_string(s), "", s, kSamplesRandomTree});
  }
  return out;
}

std::vector<Case> gravcomp_tree_cases() {
  std::vector<Case> out;
  for (unsigned s = 1; s <= kGravcompTrees; ++s) {
    out.push_back({"gravcomp_tree_seed" + std::to_string(s), "", s, kSamplesRandomTree, false, true});
  }
  return out;
}

std::vector<Case> aligned_tree_cases() {
  std::vector<Case> out;
  for (unsigned s = 1; s <= kAlignedTrees; ++s) {
    out.push_back({"aligned_tree_seed" + std::to_string(s), "", s, kSamplesRandomTree, true});
  }
  return out;
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) { return info.param.label; }

struct Loaded {
  mj::ModelPtr m;
  Model model;
};

std::unique_ptr<Loaded> load_case(const Case& c) {
  test::RandomTreeOptions options;
  options.aligned_axes = c.aligned;
  options.gravcomp = c.gravcomp;
  mj::ModelPtr m = c.path.empty()
                       ? mj::load_model_from_string(test::random_tree_mjcf(c.seed, options))
                       : test::load_problem(c.path).m;  // a gripper's held joints welded
  Model model = mj::import_model(m.get(), c.label).model;
  return std::make_unique<Loaded>(Loaded{std::move(m), std::move(model)});
}

/// ‖x − y‖∞ / max(scale, 1)
double scaled_error(const MatX<double>& x, const MatX<double>& y, double scale) {
  return (x - y).cwiseAbs().maxCoeff() / std::max(scale, 1.0);
}
double max_abs(const MatX<double>& x) { return x.cwiseAbs().maxCoeff(); }

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

/// the worst error of each check_model quantity over all cases, printed once at the end
class WorstErrors : public ::testing::Environment {
 public:
  void record(const mj::CheckEntry& e, const std::string& label) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto [it, inserted] = worst_.try_emplace(e.quantity, Worst{e.worst, e.tolerance, label});
    if (!inserted && e.worst > it->second.error) it->second = {e.worst, e.tolerance, label};
  }
  void TearDown() override {
    if (worst_.empty()) return;
    std::cout << "worst relative error per quantity over all (model, seed) cases:\n";
    for (const auto& [quantity, w] : worst_) {
      std::cout << "  " << quantity << ": " << w.error << " (tolerance " << w.tolerance << ", "
                << w.label << ")\n";
    }
  }

 private:
  struct Worst {
    double error;
    double tolerance;
    std::string label;
  };
  std::mutex mutex_;
  std::map<std::string, Worst> worst_;
};
WorstErrors* const g_worst =
    static_cast<WorstErrors*>(::testing::AddGlobalTestEnvironment(new WorstErrors));

/// a MuJoCo warning anywhere in a test fails it
class DynamicsTest : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    mj::install_error_handlers();
    const std::vector<std::string> stale = mj::take_warnings();
    ASSERT_TRUE(stale.empty()) << "MuJoCo warnings before the test:" << joined(stale);
    loaded_ = load_case(GetParam());
  }
  void TearDown() override {
    const std::vector<std::string> warnings = mj::take_warnings();
    EXPECT_TRUE(warnings.empty()) << "MuJoCo warnings:" << joined(warnings);
  }

  const Model& model() const { return loaded_->model; }
  int n() const { return loaded_->model.n; }

  /// random state (q around q_ref, v, a, τ) for sample k of this case
  struct State {
    VecX<double> q, v, a, tau;
  };
  State random_state(std::mt19937& rng) const {
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    auto random = [&](double scale) {
      VecX<double> x(n());
      for (int i = 0; i < n(); ++i) x[i] = scale * unit(rng);
      return x;
    };
    State s;
    s.q = model().q_ref + random(3.0);
    s.v = random(2.0);
    s.a = random(5.0);
    s.tau = random(5.0);
    return s;
  }
  VecX<double> random_vector(std::mt19937& rng, double scale) const {
    std::uniform_real_distribution<double> unit(-scale, scale);
    VecX<double> x(n());
    for (int i = 0; i < n(); ++i) x[i] = unit(rng);
    return x;
  }

  /// `got` solves M y = x: in residual form up to rounding in M·y, and against a dense
  /// Cholesky solve up to cond(M)·ε
  void expect_mass_solve(const MatX<double>& M, const Eigen::LLT<MatX<double>>& llt, const VecX<double>& x,
                         const VecX<double>& got) const {
    EXPECT_LE(scaled_error(M * got, x, max_abs(M) * max_abs(got)), kRounding);
    const VecX<double> expected = llt.solve(x);
    const double cond_scale = max_abs(M) * max_abs(llt.solve(MatX<double>::Identity(n(), n())));
    EXPECT_LE(max_abs(got - expected) / (cond_scale * std::max(1.0, max_abs(expected))),
              kInverseRounding * n());
  }

  std::unique_ptr<Loaded> loaded_;
};

// ---------------------------------------------------------------------------------------------
// against MuJoCo and the library's own consistency checks

TEST_P(DynamicsTest, CheckModelPassesEveryComparison) {
  const Case& c = GetParam();
  const std::vector<mj::CheckEntry> entries =
      mj::check_model(loaded_->m.get(), model(), c.samples, c.seed);
  ASSERT_FALSE(entries.empty());
  for (const mj::CheckEntry& e : entries) {
    g_worst->record(e, c.label);
    EXPECT_TRUE(e.ok()) << c.label << " (n = " << n() << "): " << e.quantity << " worst "
                        << e.worst << " > tolerance " << e.tolerance;
  }
}

// ---------------------------------------------------------------------------------------------
// internal consistency, written directly

TEST_P(DynamicsTest, CrbaColumnsAreRneaDifferences) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  const VecX<double> zero = VecX<double>::Zero(n());
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const MatX<double> M = crba(model(), data, s.q);
    // gravity and the spring force are in both terms and cancel; armature stays on the diagonal
    const VecX<double> bias = rnea(model(), data, s.q, zero, zero);
    const double scale = std::max(max_abs(M), max_abs(bias));
    for (int j = 0; j < n(); ++j) {
      const VecX<double> column = rnea(model(), data, s.q, zero, VecX<double>::Unit(n(), j)) - bias;
      EXPECT_LE(scaled_error(M.col(j), column, scale), kRounding) << "column " << j;
    }
  }
}

TEST_P(DynamicsTest, MassMatrixIsSymmetricPositiveDefinite) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const MatX<double> M = crba(model(), data, s.q);
    EXPECT_LE(scaled_error(M, M.transpose(), max_abs(M)), kRounding);
    const Eigen::SelfAdjointEigenSolver<MatX<double>> eig(M);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << "M =\n" << M;
    EXPECT_EQ(Eigen::LLT<MatX<double>>(M).info(), Eigen::Success);
  }
}

TEST_P(DynamicsTest, MassMatrixTimesInverseIsIdentity) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  const MatX<double> I = MatX<double>::Identity(n(), n());
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const MatX<double> M = crba(model(), data, s.q);
    aba_derivatives(model(), data, s.q, s.v, s.tau);
    const MatX<double> Minv = data.Minv;
    const double cond_scale = max_abs(M) * max_abs(Minv) * n();
    EXPECT_LE(max_abs(M * Minv - I) / cond_scale, kInverseRounding);
    EXPECT_LE(max_abs(Minv * M - I) / cond_scale, kInverseRounding);
    // the dense inverse from q alone, and from the factorization of an aba pass
    for (const char* how : {"minv_matrix", "minv_matrix_after_aba"}) {
      if (std::string(how) == "minv_matrix") {
        minv_matrix(model(), data, s.q);
      } else {
        aba(model(), data, s.q, s.v, s.tau);
        minv_matrix_after_aba(model(), data);
      }
      const double scale = max_abs(M) * max_abs(data.Minv) * n();
      EXPECT_LE(max_abs(M * data.Minv - I) / scale, kInverseRounding) << how;
      EXPECT_LE(max_abs(data.Minv * M - I) / scale, kInverseRounding) << how;
    }
    // the O(n) sweep gives the same inverse, column by column
    aba(model(), data, s.q, s.v, s.tau);
    for (int j = 0; j < n(); ++j) {
      const VecX<double> col = minv_apply(model(), data, VecX<double>::Unit(n(), j));
      // two different roundings of M⁻¹: each off by up to cond(M)·ε·‖M⁻¹‖
      EXPECT_LE(max_abs(col - Minv.col(j)) / (cond_scale * max_abs(Minv)), kInverseRounding)
          << "column " << j;
    }
  }
}

TEST_P(DynamicsTest, MinvApplyAfterAbaIsMassMatrixSolve) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const MatX<double> M = crba(model(), data, s.q);
    const Eigen::LLT<MatX<double>> llt(M);
    aba(model(), data, s.q, s.v, s.tau);
    for (int r = 0; r < 3; ++r) {
      const VecX<double> x = random_vector(rng, 5.0);
      expect_mass_solve(M, llt, x, minv_apply(model(), data, x));
    }
  }
}

// the sparse factor: exact (LᵀDL rebuilds M from the ancestor entries alone: no fill-in), and
// its solve is M⁻¹x; mj_solveM is compared in check_model
TEST_P(DynamicsTest, LtdlFactorRebuildsMassMatrixAndSolves) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const MatX<double> M = crba(model(), data, s.q);
    ltdl_factor(model(), data);
    // L from the ancestor entries of data.Lt only; everything else of L is zero
    MatX<double> L = MatX<double>::Identity(n(), n());
    for (int i = 0; i < n(); ++i) {
      for (int j = model().parent[i]; j >= 0; j = model().parent[j]) L(i, j) = data.Lt(j, i);
    }
    EXPECT_LE(scaled_error(L.transpose() * data.Dl.asDiagonal() * L, M, max_abs(M)), kRounding);
    EXPECT_LE(max_abs(data.Dl.cwiseProduct(data.Dlinv) - VecX<double>::Ones(n())), kRounding);
    const Eigen::LLT<MatX<double>> llt(M);
    for (int r = 0; r < 3; ++r) {
      const VecX<double> x = random_vector(rng, 5.0);
      rnea(model(), data, s.q, s.v, s.a);  // other passes leave the factor alone
      expect_mass_solve(M, llt, x, ltdl_solve(model(), data, x));
    }
  }
}

TEST_P(DynamicsTest, RneaInvertsAba) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const VecX<double> qdd = aba(model(), data, s.q, s.v, s.tau);
    const VecX<double> tau = rnea(model(), data, s.q, s.v, qdd);
    // τ is a difference of O(M·q̈) terms: scale by them
    const double scale = max_abs(crba(model(), data, s.q)) * max_abs(qdd);
    EXPECT_LE(scaled_error(tau, s.tau, scale), kRounding);
    // and the other way round, accurate up to cond(M)
    const VecX<double> tau_a = rnea(model(), data, s.q, s.v, s.a);
    const VecX<double> a = aba(model(), data, s.q, s.v, tau_a);
    const VecX<double> tau_back = rnea(model(), data, s.q, s.v, a);
    EXPECT_LE(scaled_error(tau_back, tau_a, std::max(scale, max_abs(tau_a))), kRounding);
  }
}

TEST_P(DynamicsTest, RneaDerivativesMatchFiniteDifferences) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const VecX<double> tau = rnea(model(), data, s.q, s.v, s.a);
    rnea_derivatives(model(), data, s.q, s.v, s.a);
    const MatX<double> dtau_dq = data.dtau_dq, dtau_dv = data.dtau_dv, M = data.M;
    EXPECT_LE(scaled_error(data.tau, tau, max_abs(tau)), kRounding) << "tau of rnea_derivatives";
    const auto id_q = [&](const VecX<double>& x) { return rnea(model(), data, x, s.v, s.a); };
    const auto id_v = [&](const VecX<double>& x) { return rnea(model(), data, s.q, x, s.a); };
    const auto id_a = [&](const VecX<double>& x) { return rnea(model(), data, s.q, s.v, x); };
    EXPECT_LE(scaled_error(dtau_dq, central_difference_jacobian(id_q, s.q), max_abs(dtau_dq)),
              kFiniteDifference) << "dtau_dq";
    EXPECT_LE(scaled_error(dtau_dv, central_difference_jacobian(id_v, s.v), max_abs(dtau_dv)),
              kFiniteDifference) << "dtau_dv";
    EXPECT_LE(scaled_error(M, central_difference_jacobian(id_a, s.a), max_abs(M)),
              kFiniteDifference) << "dtau_da = M";
    EXPECT_LE(scaled_error(M, crba(model(), data, s.q), max_abs(M)), kRounding) << "M vs CRBA";
  }
}

TEST_P(DynamicsTest, AbaDerivativesMatchFiniteDifferences) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    aba_derivatives(model(), data, s.q, s.v, s.tau);
    const MatX<double> da_dq = data.da_dq, da_dv = data.da_dv, da_dtau = data.Minv;
    const VecX<double> qdd = data.qdd;
    EXPECT_LE(scaled_error(qdd, aba(model(), data, s.q, s.v, s.tau), max_abs(qdd)), kRounding)
        << "qdd of aba_derivatives";
    const auto fd_q = [&](const VecX<double>& x) { return aba(model(), data, x, s.v, s.tau); };
    const auto fd_v = [&](const VecX<double>& x) { return aba(model(), data, s.q, x, s.tau); };
    const auto fd_u = [&](const VecX<double>& x) { return aba(model(), data, s.q, s.v, x); };
    EXPECT_LE(scaled_error(da_dq, central_difference_jacobian(fd_q, s.q), max_abs(da_dq)),
              kFiniteDifference) << "da_dq";
    EXPECT_LE(scaled_error(da_dv, central_difference_jacobian(fd_v, s.v), max_abs(da_dv)),
              kFiniteDifference) << "da_dv";
    EXPECT_LE(scaled_error(da_dtau, central_difference_jacobian(fd_u, s.tau), max_abs(da_dtau)),
              kFiniteDifference) << "da_dtau";
  }
}

TEST_P(DynamicsTest, RneaVjpIsTransposedDerivativesTimesW) {
  Data data(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    rnea_derivatives(model(), data, s.q, s.v, s.a);
    const MatX<double> dtau_dq = data.dtau_dq, dtau_dv = data.dtau_dv, M = data.M;
    // one rnea, then several adjoints from the same linearization point
    rnea(model(), data, s.q, s.v, s.a);
    std::vector<VecX<double>> ws = {random_vector(rng, 1.0), random_vector(rng, 10.0),
                                    VecX<double>::Unit(n(), 0), VecX<double>::Unit(n(), n() - 1)};
    for (size_t r = 0; r < ws.size(); ++r) {
      SCOPED_TRACE("w #" + std::to_string(r));
      const VecX<double>& w = ws[r];
      rnea_vjp(model(), data, w);
      const VecX<double> g_q_ref = dtau_dq.transpose() * w, g_v_ref = dtau_dv.transpose() * w,
                         g_a_ref = M * w;
      const double wn = max_abs(w);
      EXPECT_LE(scaled_error(data.g_q, g_q_ref, max_abs(dtau_dq) * wn), kRounding) << "g_q";
      EXPECT_LE(scaled_error(data.g_v, g_v_ref, max_abs(dtau_dv) * wn), kRounding) << "g_v";
      EXPECT_LE(scaled_error(data.g_a, g_a_ref, max_abs(M) * wn), kRounding) << "g_a";
    }
  }
}

TEST_P(DynamicsTest, RneaAfterAbaIsRneaAtTheAbaResult) {
  Data data(model()), ref(model());
  std::mt19937 rng(GetParam().seed);
  for (int k = 0; k < GetParam().samples; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    const State s = random_state(rng);
    const VecX<double> qdd = aba(model(), data, s.q, s.v, s.tau);
    const VecX<double> w = random_vector(rng, 1.0);
    rnea(model(), ref, s.q, s.v, qdd);
    rnea_vjp(model(), ref, w);
    const VecX<double> tau = rnea_after_aba(model(), data, s.q, s.v);
    const double scale = max_abs(crba(model(), ref, s.q)) * max_abs(qdd);
    EXPECT_LE(scaled_error(tau, ref.tau, std::max(scale, max_abs(ref.tau))), kRounding) << "tau";
    EXPECT_LE(scaled_error(tau, s.tau, std::max(scale, max_abs(s.tau))), kRounding) << "tau of aba";
    // the adjoint from it is the adjoint from rnea, and aba's factorization is still there
    rnea_vjp(model(), data, w);
    EXPECT_LE(scaled_error(data.g_q, ref.g_q, std::max(1.0, max_abs(ref.g_q))), kRounding) << "g_q";
    EXPECT_LE(scaled_error(data.g_v, ref.g_v, std::max(1.0, max_abs(ref.g_v))), kRounding) << "g_v";
    EXPECT_LE(scaled_error(data.g_a, ref.g_a, std::max(1.0, max_abs(ref.g_a))), kRounding) << "g_a";
    const VecX<double> y = minv_apply(model(), data, w);
    const MatX<double> M = crba(model(), ref, s.q);
    EXPECT_LE(scaled_error(M * y, w, max_abs(M) * max_abs(y)), kRounding)
        << "minv_apply after rnea_after_aba";
  }
}

INSTANTIATE_TEST_SUITE_P(Shipped, DynamicsTest, ::testing::ValuesIn(shipped_cases()), case_name);
INSTANTIATE_TEST_SUITE_P(RandomTrees, DynamicsTest, ::testing::ValuesIn(random_tree_cases()),
                         case_name);
INSTANTIATE_TEST_SUITE_P(AlignedTrees, DynamicsTest, ::testing::ValuesIn(aligned_tree_cases()),
                         case_name);
INSTANTIATE_TEST_SUITE_P(GravcompTrees, DynamicsTest, ::testing::ValuesIn(gravcomp_tree_cases()),
                         case_name);

}  // namespace
}  // namespace idmpc
