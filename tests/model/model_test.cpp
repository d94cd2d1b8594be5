// Model construction: the constructor's checks, and any topological link order (not only
// depth-first) gives MuJoCo's dynamics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/reference.hpp"
#include "support/random_model.hpp"

namespace idmpc {
namespace {

// ID, FD, M against MuJoCo: the same arithmetic up to rounding (as mj::CheckTolerances::mujoco)
constexpr double kMujoco = 1e-10;
// the same algorithm on relabelled links: only the order of rounding changes
constexpr double kRelabelled = 1e-10;

/// ‖x − y‖∞ / max(‖y‖∞, 1)
double relative_error(const MatX<double>& x, const MatX<double>& y) {
  return (x - y).cwiseAbs().maxCoeff() / std::max(y.cwiseAbs().maxCoeff(), 1.0);
}

/// a three-link chain with branch: 0 ← 1, 0 ← 2
std::vector<Link> small_tree() {
  std::vector<Link> links(3);
  for (int i = 0; i < 3; ++i) {
    links[i].I = Inertia<double>::from_com(1.0, Vec3<double>(0.1, 0, 0), Mat3<double>::Identity());
    links[i].X_tree.r = Vec3<double>(0.5, 0, 0);
    links[i].joint_name = "j" + std::to_string(i);
  }
  links[1].parent = 0;
  links[2].parent = 0;
  links[2].joint_type = JointType::kPrismatic;
  links[2].axis = Vec3<double>(0.6, 0, 0.8);
  return links;
}

/// the constructor throws std::invalid_argument whose message contains `needle`
void expect_rejected(const std::vector<Link>& links, const std::string& needle) {
  try {
    const Model model(links, Vec3<double>(0, 0, -9.81), "test");
    ADD_FAILURE() << "accepted; expected an error naming '" << needle << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Model, StoresTheLinksAndDerivesTheAxisIndex) {
  std::vector<Link> links = small_tree();
  links[1].axis = Vec3<double>(0, -1, 0);
  const Model model(links, Vec3<double>(0, 0, -9.81), "small");
  EXPECT_EQ(model.n, 3);
  EXPECT_EQ(model.name, "small");
  EXPECT_EQ(model.parent, (std::vector<int>{-1, 0, 0}));
  EXPECT_EQ(model.axis_index, (std::vector<int>{2, 1, -1}));
  EXPECT_EQ(model.joint_type[2], JointType::kPrismatic);
  EXPECT_EQ(model.joint_names[1], "j1");
  // link(i) gives back what was put in
  for (int i = 0; i < model.n; ++i) {
    const Link l = model.link(i);
    EXPECT_EQ(l.parent, links[i].parent);
    EXPECT_EQ(l.axis, links[i].axis);
    EXPECT_EQ(l.X_tree.r, links[i].X_tree.r);
    EXPECT_EQ(l.I.Ibar, links[i].I.Ibar);
    EXPECT_EQ(l.joint_name, links[i].joint_name);
  }
}

/// the preorder is a permutation, and the subtree_size[i] positions from preorder_index[i] hold
/// exactly link i and its descendants
void expect_subtrees_contiguous_in_preorder(const Model& model) {
  std::vector<int> sorted = model.preorder;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> identity(static_cast<size_t>(model.n));
  std::iota(identity.begin(), identity.end(), 0);
  ASSERT_EQ(sorted, identity) << "preorder is not a permutation of the links";
  for (int i = 0; i < model.n; ++i) {
    EXPECT_EQ(model.preorder[model.preorder_index[i]], i);
    std::vector<int> expected;
    for (int k = 0; k < model.n; ++k) {
      int a = k;
      while (a > i) a = model.parent[a];
      if (a == i) expected.push_back(k);
    }
    std::vector<int> held(model.preorder.begin() + model.preorder_index[i],
                          model.preorder.begin() + model.preorder_index[i] + model.subtree_size[i]);
    std::sort(held.begin(), held.end());
    EXPECT_EQ(held, expected) << "subtree of link " << i;
  }
}

TEST(Model, DerivesADepthFirstPreorderWithContiguousSubtrees) {
  // 0 ← 1 ← 3, 0 ← 2, 2 ← 4, 1 ← 5: breadth-first-like labels, not depth-first
  std::vector<Link> links(6);
  const std::vector<int> parents{-1, 0, 0, 1, 2, 1};
  for (size_t i = 0; i < links.size(); ++i) links[i].parent = parents[i];
  const Model model(links, Vec3<double>(0, 0, -9.81), "labels");
  EXPECT_EQ(model.preorder, (std::vector<int>{0, 1, 3, 5, 2, 4}));
  EXPECT_EQ(model.preorder_index, (std::vector<int>{0, 1, 4, 2, 5, 3}));
  EXPECT_EQ(model.subtree_size, (std::vector<int>{6, 3, 2, 1, 1, 1}));
  expect_subtrees_contiguous_in_preorder(model);
  // two roots, and a depth-first model, whose preorder is the identity
  const Model chain_and_root(
      [] {
        std::vector<Link> l(4);
        l[1].parent = 0;
        l[2].parent = 1;
        return l;
      }(),
      Vec3<double>::Zero(), "forest");
  EXPECT_EQ(chain_and_root.preorder, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(chain_and_root.subtree_size, (std::vector<int>{3, 2, 1, 1}));
  expect_subtrees_contiguous_in_preorder(chain_and_root);
}

TEST(Model, RejectsWhatTheAlgorithmsCannotUse) {
  expect_rejected({}, "at least one link");
  std::vector<Link> links = small_tree();
  links[1].parent = 1;
  expect_rejected(links, "link 1 (joint 'j1'): parent 1 is not an earlier link");
  links = small_tree();
  links[2].parent = -2;
  expect_rejected(links, "link 2 (joint 'j2'): parent -2");
  links = small_tree();
  links[0].axis = Vec3<double>(0, 0, 2);
  expect_rejected(links, "unit vector");
  links = small_tree();
  links[1].X_tree.E(0, 1) = 0.5;
  expect_rejected(links, "orthonormal");
  links = small_tree();
  links[2].I.m = -1;
  expect_rejected(links, "mass >= 0");
  links = small_tree();
  links[0].damping = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(links, "must be finite");
}

/// links sorted by depth (breadth-first): a topological order that is not depth-first on any
/// tree with a branch below its first level
std::vector<int> breadth_first_order(const Model& model) {
  std::vector<int> depth(model.n, 0);
  for (int i = 0; i < model.n; ++i) depth[i] = model.parent[i] < 0 ? 0 : depth[model.parent[i]] + 1;
  std::vector<int> order(model.n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return depth[a] < depth[b]; });
  return order;
}

/// true if every subtree occupies consecutive indices
bool depth_first(const Model& model) {
  const auto is_ancestor = [&](int a, int b) {
    while (b > a) b = model.parent[b];
    return b == a;
  };
  for (int i = 0; i < model.n; ++i) {
    int last = i;
    for (int k = i + 1; k < model.n; ++k) {
      if (is_ancestor(i, k)) last = k;
    }
    for (int k = i; k <= last; ++k) {
      if (!is_ancestor(i, k)) return false;
    }
  }
  return true;
}

/// The same tree with link k of the new model being link order[k] of `model`.
Model relabelled(const Model& model, const std::vector<int>& order) {
  std::vector<int> new_index(model.n);
  for (int k = 0; k < model.n; ++k) new_index[order[k]] = k;
  std::vector<Link> links;
  for (int k = 0; k < model.n; ++k) {
    Link l = model.link(order[k]);
    if (l.parent >= 0) l.parent = new_index[l.parent];
    links.push_back(l);
  }
  return Model(links, model.gravity, model.name + " (breadth-first)");
}

/// x in the relabelled order: entry k is x[order[k]]
VecX<double> permuted(const VecX<double>& x, const std::vector<int>& order) {
  VecX<double> out(x.size());
  for (size_t k = 0; k < order.size(); ++k) out[k] = x[order[k]];
  return out;
}

class BreadthFirstOrder : public ::testing::TestWithParam<std::string> {};

TEST_P(BreadthFirstOrder, AlgorithmsMatchMujocoOnATreeThatIsNotDepthFirst) {
  const std::string& which = GetParam();
  const mj::ModelPtr m = which == "tree" ? mj::load_model(IDMPC_SOURCE_DIR "/mjcf/tree.xml")
                                         : mj::load_model_from_string(test::random_tree_mjcf(
                                               7, test::RandomTreeOptions{8, 12, true}));
  const Model mujoco_order = mj::import_model(m.get(), which).model;
  const std::vector<int> order = breadth_first_order(mujoco_order);
  const Model model = relabelled(mujoco_order, order);
  ASSERT_TRUE(depth_first(mujoco_order));
  ASSERT_FALSE(depth_first(model)) << "the test needs a tree whose breadth-first order differs";
  expect_subtrees_contiguous_in_preorder(model);
  expect_subtrees_contiguous_in_preorder(mujoco_order);
  std::vector<int> identity(static_cast<size_t>(mujoco_order.n));
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(mujoco_order.preorder, identity) << "MuJoCo's order is depth-first";

  mj::Reference ref(m.get());
  Data data(model), data_mj(mujoco_order);
  const int n = model.n;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto random = [&](double scale) {
    VecX<double> x(n);
    for (int i = 0; i < n; ++i) x[i] = scale * unit(rng);
    return x;
  };
  // P maps MuJoCo's dof order to ours: (P x)[k] = x[order[k]]
  MatX<double> P = MatX<double>::Zero(n, n);
  for (int k = 0; k < n; ++k) P(k, order[k]) = 1;
  for (int s = 0; s < 3; ++s) {
    SCOPED_TRACE("sample " + std::to_string(s));
    const VecX<double> q = mujoco_order.q_ref + random(3.0), v = random(2.0), a = random(5.0),
                       tau = random(5.0), w = random(1.0);
    const VecX<double> qp = permuted(q, order), vp = permuted(v, order), ap = permuted(a, order),
                       taup = permuted(tau, order), wp = permuted(w, order);
    // against MuJoCo
    EXPECT_LE(relative_error(rnea(model, data, qp, vp, ap), P * ref.inverse(q, v, a)), kMujoco);
    EXPECT_LE(relative_error(aba(model, data, qp, vp, taup), P * ref.forward(q, v, tau)), kMujoco);
    EXPECT_LE(relative_error(crba(model, data, qp), P * ref.mass_matrix(q) * P.transpose()),
              kMujoco);
    // derivatives and adjoints against the same algorithms in MuJoCo's order
    rnea_derivatives(model, data, qp, vp, ap);
    rnea_derivatives(mujoco_order, data_mj, q, v, a);
    EXPECT_LE(relative_error(data.dtau_dq, P * data_mj.dtau_dq * P.transpose()), kRelabelled);
    EXPECT_LE(relative_error(data.dtau_dv, P * data_mj.dtau_dv * P.transpose()), kRelabelled);
    aba_derivatives(model, data, qp, vp, taup);
    aba_derivatives(mujoco_order, data_mj, q, v, tau);
    EXPECT_LE(relative_error(data.da_dq, P * data_mj.da_dq * P.transpose()), kRelabelled);
    EXPECT_LE(relative_error(data.Minv, P * data_mj.Minv * P.transpose()), kRelabelled);
    EXPECT_LE(relative_error(minv_apply(model, data, wp), P * data_mj.Minv * w), kRelabelled);
    rnea(model, data, qp, vp, ap);
    rnea_vjp(model, data, wp);
    rnea(mujoco_order, data_mj, q, v, a);
    rnea_vjp(mujoco_order, data_mj, w);
    EXPECT_LE(relative_error(data.g_q, P * data_mj.g_q), kRelabelled);
    EXPECT_LE(relative_error(data.g_v, P * data_mj.g_v), kRelabelled);
    EXPECT_LE(relative_error(data.g_a, P * data_mj.g_a), kRelabelled);
  }
  EXPECT_TRUE(mj::take_warnings().empty());
}

INSTANTIATE_TEST_SUITE_P(Trees, BreadthFirstOrder, ::testing::Values("tree", "random_tree_seed7"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace idmpc
