#include "support/random_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace idmpc::test {
namespace {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // w, x, y, z

constexpr double kPi = 3.14159265358979323846;

/// uniform draws built directly on std::mt19937, whose output sequence the standard fixes
class Rng {
 public:
  explicit Rng(unsigned seed) : engine_(seed) {}

  /// uniform in [0, 1) with 53 random bits (as genrand_res53)
  double uniform() {
    const std::uint64_t a = engine_() >> 5;
    const std::uint64_t b = engine_() >> 6;
    return (static_cast<double>(a) * 67108864.0 + static_cast<double>(b)) / 9007199254740992.0;
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// uniform integer in [lo, hi]
  int uniform_int(int lo, int hi) {
    const int k = lo + static_cast<int>(std::floor(uniform() * (hi - lo + 1)));
    return std::min(k, hi);
  }
  bool chance(double p) { return uniform() < p; }
  /// uniformly chosen element of a non-empty vector
  int pick(const std::vector<int>& xs) {
    return xs[uniform_int(0, static_cast<int>(xs.size()) - 1)];
  }

  Vec3 box(double half) {
    return {uniform(-half, half), uniform(-half, half), uniform(-half, half)};
  }

  /// uniformly distributed unit vector (rejection from the unit ball)
  Vec3 unit_vector() {
    for (;;) {
      const Vec3 v = box(1.0);
      const double n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      if (n2 > 1e-4 && n2 <= 1.0) {
        const double n = std::sqrt(n2);
        return {v[0] / n, v[1] / n, v[2] / n};
      }
    }
  }

  /// uniformly distributed rotation (Shoemake's subgroup algorithm)
  Quat rotation() {
    const double u1 = uniform(), u2 = uniform(), u3 = uniform();
    const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
    return {a * std::sin(2 * kPi * u2), a * std::cos(2 * kPi * u2), b * std::sin(2 * kPi * u3),
            b * std::cos(2 * kPi * u3)};
  }

 private:
  std::mt19937 engine_;
};

struct Joint {
  bool slide = false;
  Vec3 pos{};
  Vec3 axis{0, 0, 1};
  double ref = 0, stiffness = 0, springref = 0, damping = 0, armature = 0, gear = 1;
};

struct Body {
  int parent = -1;  // -1: world
  Vec3 pos{};
  Quat quat{1, 0, 0, 0};
  double mass = 1;
  double gravcomp = 0;
  Vec3 ipos{};
  Quat iquat{1, 0, 0, 0};
  Vec3 inertia{};
  std::vector<Joint> joints;
  std::vector<int> children;
};

/// placement, mass and inertia of a body; a link of random length with a box-shaped mass
void randomize_body(Rng& rng, Body& body) {
  const double length = rng.uniform(0.1, 0.8);
  const Vec3 dir = rng.unit_vector();
  body.pos = {length * dir[0], length * dir[1], length * dir[2]};
  body.quat = rng.rotation();
  body.mass = rng.uniform(0.2, 3.0);
  body.ipos = rng.box(0.15);
  body.iquat = rng.rotation();
  // principal moments of a uniform box: positive and strictly triangle-inequality satisfying
  const double a = rng.uniform(0.1, 0.8), b = rng.uniform(0.1, 0.8), c = rng.uniform(0.1, 0.8);
  const double k = body.mass / 12.0;
  body.inertia = {k * (b * b + c * c), k * (a * a + c * c), k * (a * a + b * b)};
}

void randomize_joint(Rng& rng, Joint& joint, bool slide, bool aligned) {
  joint.slide = slide;
  joint.pos = rng.box(0.1);
  joint.axis = rng.unit_vector();
  if (aligned) {
    size_t k = 0;
    for (size_t c = 1; c < 3; ++c) {
      if (std::abs(joint.axis[c]) > std::abs(joint.axis[k])) k = c;
    }
    const double sign = joint.axis[k] < 0 ? -1.0 : 1.0;
    joint.axis = {0, 0, 0};
    joint.axis[k] = sign;
  }
  // slides move metres, hinges radians: keep references and spring points moderate for both
  const double span = slide ? 0.1 : 0.6;
  joint.ref = rng.chance(0.5) ? rng.uniform(-span, span) : 0.0;
  joint.armature = rng.chance(0.7) ? rng.uniform(0.0, 0.1) : 0.0;
  joint.damping = rng.chance(0.7) ? rng.uniform(0.0, 0.5) : 0.0;
  if (rng.chance(0.5)) {
    joint.stiffness = rng.uniform(0.0, 3.0);
    joint.springref = rng.uniform(-span, span);
  }
  joint.gear = rng.uniform(0.5, 3.0);
}

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", x);
  return buf;
}

template <std::size_t K>
std::string nums(const std::array<double, K>& xs) {
  std::string out;
  for (std::size_t i = 0; i < K; ++i) out += (i ? " " : "") + num(xs[i]);
  return out;
}

struct Writer {
  const std::vector<Body>& bodies;
  std::string out;

  void body(int id, int depth) {
    const Body& b = bodies[id];
    const std::string pad(static_cast<std::size_t>(2 * depth), ' ');
    out += pad + "<body name=\"b" + std::to_string(id) + "\" pos=\"" + nums(b.pos) + "\" quat=\"" +
           nums(b.quat) + "\"" + (b.gravcomp != 0 ? " gravcomp=\"" + num(b.gravcomp) + "\"" : "") + ">\n";
    for (std::size_t j = 0; j < b.joints.size(); ++j) {
      const Joint& jt = b.joints[j];
      out += pad + "  <joint name=\"" + joint_name(id, j) + "\" type=\"" +
             (jt.slide ? "slide" : "hinge") + "\" pos=\"" + nums(jt.pos) + "\" axis=\"" +
             nums(jt.axis) + "\" ref=\"" + num(jt.ref) + "\" stiffness=\"" + num(jt.stiffness) +
             "\" springref=\"" + num(jt.springref) + "\" damping=\"" + num(jt.damping) +
             "\" armature=\"" + num(jt.armature) + "\"/>\n";
    }
    out += pad + "  <inertial pos=\"" + nums(b.ipos) + "\" quat=\"" + nums(b.iquat) + "\" mass=\"" +
           num(b.mass) + "\" diaginertia=\"" + nums(b.inertia) + "\"/>\n";
    // massless geoms for looks only: a sphere at the origin, a capsule to each child
    out += pad + "  <geom type=\"sphere\" size=\"0.03\" mass=\"0\"/>\n";
    for (int child : b.children) {
      out += pad + "  <geom type=\"capsule\" fromto=\"0 0 0 " + nums(bodies[child].pos) +
             "\" size=\"0.015\" mass=\"0\"/>\n";
    }
    for (int child : b.children) body(child, depth + 1);
    out += pad + "</body>\n";
  }

  static std::string joint_name(int body, std::size_t j) {
    return "j" + std::to_string(body) + (j == 0 ? "" : "_" + std::to_string(j));
  }
};

}  // namespace

std::string random_tree_mjcf(unsigned seed, const RandomTreeOptions& options) {
  if (options.min_dofs < 1 || options.max_dofs < options.min_dofs) {
    throw std::invalid_argument(
        "random_tree_mjcf: expected 1 <= min_dofs <= max_dofs, got min_dofs=" +
        std::to_string(options.min_dofs) + ", max_dofs=" + std::to_string(options.max_dofs));
  }
  Rng rng(seed);
  const int ndof = rng.uniform_int(options.min_dofs, options.max_dofs);

  // joints per jointed body: mostly one, some two; at least one two-joint body when ndof >= 2
  std::vector<int> counts;
  for (int left = ndof; left > 0;) {
    const int k = (left >= 2 && rng.chance(0.3)) ? 2 : 1;
    counts.push_back(k);
    left -= k;
  }
  if (ndof >= 2 && std::find(counts.begin(), counts.end(), 2) == counts.end()) {
    counts.pop_back();
    counts[rng.uniform_int(0, static_cast<int>(counts.size()) - 1)] = 2;
  }
  const int njointed = static_cast<int>(counts.size());

  // topology of the jointed bodies: chain-like or branching; one forced branch if none arose
  std::vector<int> jparent(njointed, -1);
  std::vector<int> nchildren(njointed, 0);
  bool branched = false;
  for (int i = 1; i < njointed; ++i) {
    int p;
    std::vector<int> with_child;
    for (int j = 0; j < i; ++j) {
      if (nchildren[j] >= 1) with_child.push_back(j);
    }
    if (!branched && i == njointed - 1 && !with_child.empty()) {
      p = rng.pick(with_child);
    } else if (rng.chance(0.08)) {
      p = -1;  // another root hanging from the world
    } else if (rng.chance(0.5)) {
      p = i - 1;
    } else {
      p = rng.uniform_int(0, i - 1);
    }
    jparent[i] = p;
    if (p >= 0 && ++nchildren[p] >= 2) branched = true;
  }

  // welded bodies between a jointed body and its jointed parent (at least one when possible)
  std::vector<bool> welded_above(njointed, false);
  bool any_welded_between = false;
  for (int i = 1; i < njointed; ++i) {
    if (jparent[i] >= 0 && rng.chance(0.2)) {
      welded_above[i] = true;
      any_welded_between = true;
    }
  }
  if (!any_welded_between) {
    std::vector<int> candidates;
    for (int i = 1; i < njointed; ++i) {
      if (jparent[i] >= 0) candidates.push_back(i);
    }
    if (!candidates.empty()) {
      welded_above[rng.pick(candidates)] = true;
    }
  }

  // slide joints with probability 0.25; at least one when ndof >= 3
  std::vector<bool> slide(ndof, false);
  bool any_slide = false;
  for (int d = 0; d < ndof; ++d) {
    slide[d] = rng.chance(0.25);
    any_slide = any_slide || slide[d];
  }
  if (ndof >= 3 && !any_slide) slide[rng.uniform_int(0, ndof - 1)] = true;

  // materialize the bodies (jointed body i gets its welded parent first, if any)
  std::vector<Body> bodies;
  std::vector<int> body_of(njointed, -1);
  int dof = 0;
  auto add_body = [&](int parent) {
    Body b;
    b.parent = parent;
    randomize_body(rng, b);
    bodies.push_back(b);
    const int id = static_cast<int>(bodies.size()) - 1;
    if (parent >= 0) bodies[parent].children.push_back(id);
    return id;
  };
  for (int i = 0; i < njointed; ++i) {
    const int jp = jparent[i];
    int parent = jp >= 0 ? body_of[jp] : -1;
    if (welded_above[i]) parent = add_body(parent);
    const int id = add_body(parent);
    body_of[i] = id;
    for (int k = 0; k < counts[i]; ++k, ++dof) {
      Joint j;
      randomize_joint(rng, j, slide[dof], options.aligned_axes);
      bodies[id].joints.push_back(j);
    }
  }
  // welded leaves: one or two, hanging from random jointed bodies; the first one makes a branch
  // point if the tree has none yet
  std::vector<int> leaf_parents = body_of;
  const bool has_branch = std::any_of(bodies.begin(), bodies.end(),
                                      [](const Body& b) { return b.children.size() >= 2; });
  if (!has_branch) {
    std::vector<int> with_child;
    for (int id : body_of) {
      if (!bodies[id].children.empty()) with_child.push_back(id);
    }
    if (!with_child.empty()) leaf_parents = with_child;
  }
  const int nleaves = rng.uniform_int(1, 2);
  for (int k = 0; k < nleaves; ++k) {
    add_body(rng.pick(leaf_parents));
    leaf_parents = body_of;
  }

  if (options.gravcomp) {
    Rng extra(seed + 7919u);
    for (Body& b : bodies) {
      if (extra.chance(0.5)) b.gravcomp = extra.chance(0.3) ? 1.0 : extra.uniform(0.05, 1.5);
    }
    if (std::all_of(bodies.begin(), bodies.end(), [](const Body& b) { return b.gravcomp == 0; })) {
      bodies.back().gravcomp = 0.5;
    }
  }
  Writer w{bodies, {}};
  w.out += "<mujoco model=\"random_tree_" + std::to_string(seed) + "\">\n";
  w.out += "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n";
  w.out += "  <option timestep=\"0.001\">\n    <flag contact=\"disable\"/>\n  </option>\n";
  w.out += "  <default>\n    <geom contype=\"0\" conaffinity=\"0\" rgba=\"0.9 0.55 0.2 1\"/>\n";
  w.out += "    <joint limited=\"false\"/>\n  </default>\n";
  w.out += "  <worldbody>\n";
  for (std::size_t id = 0; id < bodies.size(); ++id) {
    if (bodies[id].parent < 0) w.body(static_cast<int>(id), 2);
  }
  w.out += "  </worldbody>\n";
  if (options.with_actuators) {
    w.out += "  <actuator>\n";
    for (std::size_t id = 0; id < bodies.size(); ++id) {
      for (std::size_t j = 0; j < bodies[id].joints.size(); ++j) {
        const std::string name = Writer::joint_name(static_cast<int>(id), j);
        w.out += "    <motor name=\"" + name + "\" joint=\"" + name + "\" gear=\"" +
                 num(bodies[id].joints[j].gear) + "\"/>\n";
      }
    }
    w.out += "  </actuator>\n";
  }
  w.out += "</mujoco>\n";
  return w.out;
}

}  // namespace idmpc::test
