// FrameKinematics against MuJoCo: position, rotation and both Jacobian halves of every named
// site and body of every shipped model and of random trees (with sites added on jointed and
// welded bodies, on a welded body on the world and on the world itself) at random q; the
// adjoint product against Jᵀf; the SIMD-pack path against the double path lane by lane; and the
// frame checks and import_frame's messages.
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

#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/spatial/pack.hpp"
#include "support/problems.hpp"
#include "support/lanes.hpp"
#include "support/random_model.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

// MuJoCo composes the same placements through quaternions: both sides round in O(depth) flops
// of O(1) numbers, relative to max(1, |value|)
constexpr double kMujoco = 1e-12;
// the same arithmetic in SIMD lanes and in doubles; only Eigen's reduction order may differ
constexpr double kLanes = 1e-14;
// Jᵀf summed over rows against the O(depth) sweep, relative to max(1, |J|·|f|)
constexpr double kAdjoint = 1e-13;
constexpr int kRandomTrees = 40;
constexpr int kSamples = 3;  // random q per case
using P = StagePack;
constexpr int kW = kStageLanes;

struct Case {
  std::string label;  // "<file stem>" or "random_tree_seed<k>"
  std::string path;   // empty for a random tree
  unsigned seed = 0;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << c.label << (c.path.empty() ? " (random_tree_mjcf(" + std::to_string(c.seed) + ") with sites)"
                                    : " (" + c.path + ")");
}

std::string sanitize(std::string s) {
  for (char& ch : s) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return s;
}

std::vector<Case> all_cases() {
  std::vector<Case> out;
  unsigned seed = 1;
  for (const std::string& path : test::shipped_model_paths()) {
    out.push_back({sanitize(std::filesystem::path(path).stem().string()), path, seed++});
  }
  for (unsigned s = 1; s <= kRandomTrees; ++s) out.push_back({"random_tree_seed" + std::to_string(s), "", s});
  return out;
}

// "x y z" of uniform numbers in [−scale, scale]
std::string random_numbers(std::mt19937& rng, int count, double scale) {
  std::uniform_real_distribution<double> unit(-scale, scale);
  std::string out;
  for (int k = 0; k < count; ++k) out += (k ? " " : "") + std::to_string(unit(rng));
  return out;
}

// a site at a random pose on every body of a random tree (after its opening tag), a welded body
// with a site on the world, and a site on the world itself
std::string random_tree_with_sites(unsigned seed) {
  const std::string xml = test::random_tree_mjcf(seed);
  std::mt19937 rng(seed + 1000);
  const auto site = [&](const std::string& name, const std::string& pad) {
    return pad + "<site name=\"" + name + "\" pos=\"" + random_numbers(rng, 3, 0.3) + "\" quat=\"" +
           random_numbers(rng, 4, 1.0) + "\"/>\n";
  };
  std::string out;
  std::size_t at = 0;
  while (at < xml.size()) {
    const std::size_t end = xml.find('\n', at);
    const std::string line = xml.substr(at, end - at + 1);
    at = end + 1;
    out += line;
    const std::size_t body = line.find("<body name=\"");
    if (body != std::string::npos) {
      const std::size_t name_begin = body + 12;
      const std::string name = line.substr(name_begin, line.find('"', name_begin) - name_begin);
      out += site("s_" + name, std::string(body + 2, ' '));
    } else if (line.find("<worldbody>") != std::string::npos) {
      out += site("s_world", "    ");
      out += "    <body name=\"fixed\" pos=\"" + random_numbers(rng, 3, 0.5) + "\" quat=\"" +
             random_numbers(rng, 4, 1.0) + "\">\n";
      out += site("s_fixed", "      ");
      out += "    </body>\n";
    }
  }
  return out;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

double max_abs(const MatX<double>& x) { return x.size() ? x.cwiseAbs().maxCoeff() : 0.0; }
double scaled_error(const MatX<double>& x, const MatX<double>& y) {
  return max_abs(x - y) / std::max(1.0, max_abs(y));
}

/// the worst error of each quantity against MuJoCo over all cases, printed once at the end
class WorstErrors : public ::testing::Environment {
 public:
  void record(const std::string& quantity, double error, const std::string& where) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto [it, inserted] = worst_.try_emplace(quantity, error, where);
    if (!inserted && error > it->second.first) it->second = {error, where};
  }
  void count_frame(bool site) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++(site ? sites_ : bodies_);
  }
  void TearDown() override {
    if (worst_.empty()) return;
    std::cout << sites_ << " site and " << bodies_ << " body frames compared with MuJoCo at " << kSamples
              << " q each; worst scaled error per quantity (tolerance " << kMujoco << "):\n";
    for (const auto& [quantity, w] : worst_) std::cout << "  " << quantity << ": " << w.first << " (" << w.second << ")\n";
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::pair<double, std::string>> worst_;
  int sites_ = 0, bodies_ = 0;
};
WorstErrors* const g_worst = static_cast<WorstErrors*>(::testing::AddGlobalTestEnvironment(new WorstErrors));

/// a frame to check: a named site, or a named body whose name no site has
struct Target {
  std::string name;
  int site = -1;  // MuJoCo site id, or −1 for a body
  int body = -1;
};

class KinematicsTest : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    mj::install_error_handlers();
    const std::vector<std::string> stale = mj::take_warnings();
    ASSERT_TRUE(stale.empty()) << "MuJoCo warnings before the test:" << joined(stale);
    const Case& c = GetParam();
    // shipped models as the controller sees them: a gripper's held joints welded
    m_ = c.path.empty() ? mj::load_model_from_string(random_tree_with_sites(c.seed)) : test::load_problem(c.path).m;
    model_ = std::make_unique<Model>(mj::import_model(m_.get(), c.label).model);
    for (int s = 0; s < m_->nsite; ++s) {
      const char* name = mj_id2name(m_.get(), mjOBJ_SITE, s);
      if (name && name[0]) targets_.push_back({name, s, m_->site_bodyid[s]});
    }
    for (int b = 0; b < m_->nbody; ++b) {
      const char* name = mj_id2name(m_.get(), mjOBJ_BODY, b);
      if (name && name[0] && mj_name2id(m_.get(), mjOBJ_SITE, name) < 0) targets_.push_back({name, -1, b});
    }
  }
  void TearDown() override {
    const std::vector<std::string> warnings = mj::take_warnings();
    EXPECT_TRUE(warnings.empty()) << "MuJoCo warnings:" << joined(warnings);
  }

  int n() const { return model_->n; }
  VecX<double> random_q(std::mt19937& rng) const {
    std::uniform_real_distribution<double> unit(-3.0, 3.0);
    VecX<double> q = model_->q_ref;
    for (int i = 0; i < n(); ++i) q[i] += unit(rng);
    return q;
  }
  Vec3<double> random_vec3(std::mt19937& rng) const {
    std::uniform_real_distribution<double> unit(-2.0, 2.0);
    return Vec3<double>(unit(rng), unit(rng), unit(rng));
  }

  mj::ModelPtr m_;
  std::unique_ptr<Model> model_;
  std::vector<Target> targets_;
};

TEST_P(KinematicsTest, PlacementAndJacobianMatchMujoco) {
  const Case& c = GetParam();
  ASSERT_FALSE(targets_.empty());
  const mj::DataPtr d = mj::make_data(m_.get());
  std::mt19937 rng(c.seed);
  MatX<double> jacp(3, n()), jacr(3, n());  // MuJoCo's, row-major there: read transposed
  FrameKinematics<double>::Jacobian J(6, n()), J_mj(6, n());
  for (const Target& t : targets_) g_worst->count_frame(t.site >= 0);
  for (int k = 0; k < kSamples; ++k) {
    const VecX<double> q = random_q(rng);
    mju_copy(d->qpos, q.data(), n());
    mj_kinematics(m_.get(), d.get());
    mj_comPos(m_.get(), d.get());
    for (const Target& t : targets_) {
      const std::string where = c.label + " " + (t.site >= 0 ? "site '" : "body '") + t.name + "'";
      SCOPED_TRACE(where + ", sample " + std::to_string(k));
      const Frame frame = mj::import_frame(m_.get(), t.name, c.label);
      FrameKinematics<double> fk(*model_, frame);
      fk.compute(*model_, q);
      fk.jacobian(J);
      // the pose without a workspace (frame_pose) is the workspace's, up to the order of products
      Vec3<double> p;
      Mat3<double> R;
      frame_pose(*model_, frame, q, p, R);
      EXPECT_LE((p - fk.position()).cwiseAbs().maxCoeff(), 1e-12 * (1 + p.norm()));
      EXPECT_LE((R - fk.rotation()).cwiseAbs().maxCoeff(), 1e-12);
      const mjtNum* xpos = t.site >= 0 ? d->site_xpos + 3 * t.site : d->xpos + 3 * t.body;
      const mjtNum* xmat = t.site >= 0 ? d->site_xmat + 9 * t.site : d->xmat + 9 * t.body;
      std::vector<mjtNum> jp(3 * n()), jr(3 * n());
      if (t.site >= 0) {
        mj_jacSite(m_.get(), d.get(), jp.data(), jr.data(), t.site);
      } else {
        mj_jacBody(m_.get(), d.get(), jp.data(), jr.data(), t.body);
      }
      using Rows3 = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>;
      J_mj.topRows<3>() = Eigen::Map<const Rows3>(jp.data(), 3, n());
      J_mj.bottomRows<3>() = Eigen::Map<const Rows3>(jr.data(), 3, n());
      const Vec3<double> p_mj(xpos[0], xpos[1], xpos[2]);
      const Mat3<double> R_mj = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(xmat);

      const double e_p = scaled_error(fk.position(), p_mj);
      const double e_R = scaled_error(fk.rotation(), R_mj);
      const double e_jp = scaled_error(J.topRows<3>(), J_mj.topRows<3>());
      const double e_jr = scaled_error(J.bottomRows<3>(), J_mj.bottomRows<3>());
      g_worst->record("position", e_p, where);
      g_worst->record("rotation", e_R, where);
      g_worst->record("jacp", e_jp, where);
      g_worst->record("jacr", e_jr, where);
      EXPECT_LE(e_p, kMujoco) << "p = " << fk.position().transpose() << ", MuJoCo " << p_mj.transpose();
      EXPECT_LE(e_R, kMujoco) << "R =\n" << fk.rotation() << "\nMuJoCo\n" << R_mj;
      EXPECT_LE(e_jp, kMujoco) << "jacp =\n" << J.topRows<3>() << "\nMuJoCo\n" << J_mj.topRows<3>();
      EXPECT_LE(e_jr, kMujoco) << "jacr =\n" << J.bottomRows<3>() << "\nMuJoCo\n" << J_mj.bottomRows<3>();
      // columns of non-ancestors are zero, and the ancestors are those of the frame's link
      std::vector<bool> ancestor(n(), false);
      for (int i : fk.path()) ancestor[i] = true;
      for (int i = frame.link; i >= 0; i = model_->parent[i]) EXPECT_TRUE(ancestor[i]) << "link " << i;
      for (int i = 0; i < n(); ++i) {
        if (!ancestor[i]) {
          EXPECT_EQ(J.col(i).cwiseAbs().maxCoeff(), 0.0) << "column " << i;
        }
      }
    }
  }
}

TEST_P(KinematicsTest, JacobianTransposeProductIsJtFAndRefsAndBlocksWork) {
  std::mt19937 rng(GetParam().seed + 7);
  FrameKinematics<double>::Jacobian J(6, n());
  for (const Target& t : targets_) {
    SCOPED_TRACE(t.name);
    const Frame frame = mj::import_frame(m_.get(), t.name, GetParam().label);
    FrameKinematics<double> fk(*model_, frame);
    for (int k = 0; k < kSamples; ++k) {
      fk.compute(*model_, random_q(rng));
      fk.jacobian(J);
      const Vec3<double> f_lin = random_vec3(rng), f_ang = random_vec3(rng);
      Vec6<double> f;
      f << f_lin, f_ang;
      VecX<double> g0(n());
      for (int i = 0; i < n(); ++i) g0[i] = random_vec3(rng)[0];
      VecX<double> g = g0;
      fk.add_jacobian_transpose_times(f_lin, f_ang, g);
      const VecX<double> expected = J.transpose() * f;
      EXPECT_LE(max_abs(g - g0 - expected) / std::max(1.0, max_abs(J) * max_abs(f)), kAdjoint)
          << "got " << (g - g0).transpose() << "\nJᵀf " << expected.transpose();
      // into a segment of a longer vector too, directly and through an Eigen::Ref
      VecX<double> longer = VecX<double>::Zero(n() + 3);
      fk.add_jacobian_transpose_times(f_lin, f_ang, longer.segment(1, n()));
      Eigen::Ref<VecX<double>> g_ref = longer.segment(1, n());
      fk.add_jacobian_transpose_times(f_lin, f_ang, g_ref);
      EXPECT_LE(max_abs(longer.segment(1, n()) - 2 * expected) / std::max(1.0, max_abs(J) * max_abs(f)), kAdjoint);
      EXPECT_EQ(longer[0], 0.0);
      EXPECT_EQ(longer[n() + 1], 0.0);
    }
    // q through an Eigen::Ref, J into a block of a larger dynamic matrix
    const VecX<double> q = random_q(rng);
    fk.compute(*model_, q);
    fk.jacobian(J);
    const Eigen::Ref<const VecX<double>> q_ref = q;
    FrameKinematics<double> fk_ref(*model_, frame);
    fk_ref.compute(*model_, q_ref);
    MatX<double> big = MatX<double>::Constant(8, n(), 7.0);
    fk_ref.jacobian(big.middleRows(1, 6));
    EXPECT_EQ(big.middleRows(1, 6), J);
    EXPECT_EQ(fk_ref.position(), fk.position());
    EXPECT_TRUE((big.row(0).array() == 7.0).all() && (big.row(7).array() == 7.0).all());
  }
}

TEST_P(KinematicsTest, PackLanesEqualTheDoublePath) {
  std::mt19937 rng(GetParam().seed + 13);
  FrameKinematics<double>::Jacobian J(6, n());
  FrameKinematics<P>::Jacobian Jp(6, n());
  for (const Target& t : targets_) {
    SCOPED_TRACE(t.name);
    const Frame frame = mj::import_frame(m_.get(), t.name, GetParam().label);
    FrameKinematics<double> fk(*model_, frame);
    FrameKinematics<P> fp(*model_, frame);
    // each lane its own q and force
    std::vector<VecX<double>> q(kW);
    std::vector<Vec3<double>> f_lin(kW), f_ang(kW);
    for (int l = 0; l < kW; ++l) {
      q[l] = random_q(rng);
      f_lin[l] = random_vec3(rng);
      f_ang[l] = random_vec3(rng);
    }
    const VecX<P> qp = test::packed<P>(q);
    const Vec3<P> f_lin_p = test::packed<P>(f_lin), f_ang_p = test::packed<P>(f_ang);
    fp.compute(*model_, qp);
    fp.jacobian(Jp);
    VecX<P> gp = VecX<P>::Constant(n(), P(0.0));
    fp.add_jacobian_transpose_times(f_lin_p, f_ang_p, gp);
    for (int l = 0; l < kW; ++l) {
      SCOPED_TRACE("lane " + std::to_string(l));
      fk.compute(*model_, q[l]);
      fk.jacobian(J);
      VecX<double> g = VecX<double>::Zero(n());
      fk.add_jacobian_transpose_times(f_lin[l], f_ang[l], g);
      EXPECT_LE(scaled_error(test::lane(fp.position(), l), fk.position()), kLanes);
      EXPECT_LE(scaled_error(test::lane(fp.rotation(), l), fk.rotation()), kLanes);
      EXPECT_LE(scaled_error(test::lane(Jp, l), J), kLanes);
      EXPECT_LE(scaled_error(test::lane(gp, l), g), kLanes);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, KinematicsTest, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.label; });

// ---------------------------------------------------------------------------------------------
// the frame checks and import_frame's messages

const std::string& panda_path() {
  static const std::string path = std::string(IDMPC_SOURCE_DIR) + "/mjcf/panda.xml";
  return path;
}

TEST(FrameImport, UnknownNameIsOneLineNamingModelNameAndSites) {
  mj::install_error_handlers();
  const mj::ModelPtr m = mj::load_model(panda_path());
  try {
    mj::import_frame(m.get(), "tool", "panda.xml");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "model 'panda.xml' has no site or body 'tool' (sites: tip)");
  }
}

TEST(FrameImport, ModelWithoutNamedSitesSaysSo) {
  mj::install_error_handlers();
  const mj::ModelPtr m = mj::load_model_from_string(test::random_tree_mjcf(3));
  try {
    mj::import_frame(m.get(), "tip", "tree3");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "model 'tree3' has no site or body 'tip' (it has no named sites)");
  }
}

TEST(FrameImport, SiteComesBeforeABodyOfTheSameNameAndWorldIsTheBase) {
  mj::install_error_handlers();
  const mj::ModelPtr m = mj::load_model_from_string(R"(
<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="j" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
      <site name="a_site" pos="0.1 0 0"/>
      <body name="b" pos="0.5 0 0">
        <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
        <site name="a" pos="0 0.2 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  const Frame site = mj::import_frame(m.get(), "a", "inline");
  EXPECT_EQ(site.name, "site 'a'");
  EXPECT_EQ(site.link, 0);
  EXPECT_LE((site.placement.r - Vec3<double>(0.5, 0.2, 0)).norm(), 1e-15);
  const Frame body = mj::import_frame(m.get(), "b", "inline");
  EXPECT_EQ(body.name, "body 'b'");
  const Frame world = mj::import_frame(m.get(), "world", "inline");
  EXPECT_EQ(world.link, -1);
  EXPECT_EQ(world.placement.r, Vec3<double>::Zero());
}

TEST(FrameCheck, RejectsBadLinksAndPlacementsNamingTheFrame) {
  mj::install_error_handlers();
  const mj::ModelPtr m = mj::load_model(panda_path());
  const Model model = mj::import_model(m.get(), "panda").model;
  const auto message = [&](const Frame& f) -> std::string {
    try {
      FrameKinematics<double> fk(model, f);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  Frame f{"site 'tool'", model.n, {}};
  EXPECT_EQ(message(f), "site 'tool' of model 'panda': link " + std::to_string(model.n) +
                            " is not a link of the model: expected -1 (the base) to " + std::to_string(model.n - 1));
  f.link = -2;
  EXPECT_NE(message(f).find("link -2 is not a link"), std::string::npos);
  f.link = 1;
  f.placement.r[1] = std::nan("");
  EXPECT_EQ(message(f), "site 'tool' of model 'panda': placement is not finite");
  f.placement.r[1] = 0;
  f.placement.E(0, 1) = 0.1;
  EXPECT_NE(message(f).find("site 'tool' of model 'panda': placement rotation must be orthonormal"), std::string::npos);
  f.placement.E = -Mat3<double>::Identity();  // a reflection
  EXPECT_NE(message(f).find("determinant +1"), std::string::npos);
  f.placement.E.setIdentity();
  EXPECT_EQ(message(f), "no exception");
}

}  // namespace
}  // namespace idmpc
