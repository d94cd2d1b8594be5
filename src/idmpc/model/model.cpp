#include "idmpc/model/model.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

namespace idmpc {
namespace {

// unit-norm and orthonormality tolerance: the importer normalizes, so only rounding remains
constexpr double kUnitTolerance = 1e-9;

std::string label(const std::vector<Link>& links, size_t i) {
  const std::string& name = links[i].joint_name;
  return "link " + std::to_string(i) + (name.empty() ? "" : " (joint '" + name + "')");
}

// every check of the constructor, before any member is made; returns n
int checked_size(const std::vector<Link>& links, const Vec3<double>& gravity,
                 const std::string& name) {
  const std::string where = name.empty() ? "model" : "model '" + name + "'";
  if (links.empty()) throw std::invalid_argument(where + ": expected at least one link, got none");
  if (!gravity.allFinite()) throw std::invalid_argument(where + ": gravity is not finite");
  for (size_t i = 0; i < links.size(); ++i) {
    const Link& l = links[i];
    const auto fail = [&](const std::string& what) {
      throw std::invalid_argument(where + ", " + label(links, i) + ": " + what);
    };
    if (l.parent < -1 || l.parent >= static_cast<int>(i)) {
      fail("parent " + std::to_string(l.parent) +
           " is not an earlier link or -1 (expected topological order)");
    }
    if (!l.axis.allFinite() || std::abs(l.axis.norm() - 1.0) > kUnitTolerance) {
      fail("joint axis must be a unit vector, got norm " + std::to_string(l.axis.norm()));
    }
    const Mat3<double>& E = l.X_tree.E;
    if (!E.allFinite() || !l.X_tree.r.allFinite() ||
        (E * E.transpose() - Mat3<double>::Identity()).cwiseAbs().maxCoeff() > kUnitTolerance) {
      fail("X_tree must be finite with an orthonormal rotation");
    }
    if (!std::isfinite(l.I.m) || !l.I.h.allFinite() || !l.I.Ibar.allFinite() || l.I.m < 0) {
      fail("inertia must be finite with mass >= 0, got mass " + std::to_string(l.I.m));
    }
    if (!std::isfinite(l.I_gravcomp.m) || !l.I_gravcomp.h.allFinite() || !l.I_gravcomp.Ibar.allFinite()) {
      fail("gravity-compensated inertia must be finite, got mass " + std::to_string(l.I_gravcomp.m));
    }
    for (double x : {l.q_ref, l.armature, l.damping, l.stiffness, l.q_spring, l.friction, l.friction_velocity}) {
      if (!std::isfinite(x)) fail("q_ref, armature, damping, stiffness, q_spring and friction must be finite");
    }
    if (l.friction < 0) fail("friction loss must be >= 0, got " + std::to_string(l.friction));
    if (l.friction > 0 && !(l.friction_velocity > 0)) {
      fail("friction loss " + std::to_string(l.friction) + " needs a positive smoothing velocity, got " +
           std::to_string(l.friction_velocity));
    }
  }
  return static_cast<int>(links.size());
}

template <typename T> std::vector<T> gather(const std::vector<Link>& links, T Link::*field) {
  std::vector<T> out;
  out.reserve(links.size());
  for (const Link& l : links) out.push_back(l.*field);
  return out;
}

VecX<double> gather_vector(const std::vector<Link>& links, double Link::*field) {
  VecX<double> out(static_cast<Eigen::Index>(links.size()));
  for (size_t i = 0; i < links.size(); ++i) out[static_cast<Eigen::Index>(i)] = links[i].*field;
  return out;
}

std::vector<int> axis_indices(const std::vector<Link>& links) {
  std::vector<int> out(links.size(), -1);
  for (size_t i = 0; i < links.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (std::abs(links[i].axis[k]) == 1.0) out[i] = k;
    }
  }
  return out;
}

// depth-first preorder, children visited in index order; parents come before their children
std::vector<int> depth_first_preorder(const std::vector<Link>& links) {
  const int n = static_cast<int>(links.size());
  std::vector<std::vector<int>> children(links.size());
  std::vector<int> stack;
  for (int i = n - 1; i >= 0; --i) {
    const int p = links[static_cast<size_t>(i)].parent;
    if (p >= 0) {
      children[static_cast<size_t>(p)].push_back(i);  // descending: popped ascending
    } else {
      stack.push_back(i);
    }
  }
  std::vector<int> out;
  out.reserve(links.size());
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    out.push_back(i);
    const std::vector<int>& c = children[static_cast<size_t>(i)];
    stack.insert(stack.end(), c.begin(), c.end());
  }
  return out;
}

std::vector<int> inverse_permutation(const std::vector<int>& order) {
  std::vector<int> out(order.size());
  for (size_t t = 0; t < order.size(); ++t) out[static_cast<size_t>(order[t])] = static_cast<int>(t);
  return out;
}

std::vector<int> subtree_sizes(const std::vector<Link>& links) {
  std::vector<int> out(links.size(), 1);
  for (size_t i = links.size(); i-- > 0;) {
    if (links[i].parent >= 0) out[static_cast<size_t>(links[i].parent)] += out[i];
  }
  return out;
}

std::vector<int> joints_where(const std::vector<Link>& links, bool actuated) {
  std::vector<int> out;
  for (size_t i = 0; i < links.size(); ++i) {
    if (links[i].actuated == actuated) out.push_back(static_cast<int>(i));
  }
  return out;
}

bool any_gravcomp(const std::vector<Link>& links, const Vec3<double>& gravity) {
  if (gravity.isZero(0)) return false;
  return std::any_of(links.begin(), links.end(), [](const Link& l) {
    return l.I_gravcomp.m != 0 || !l.I_gravcomp.h.isZero(0);
  });
}

std::vector<int> run_starts(const std::vector<Link>& links) {
  std::vector<int> out(links.size());
  for (size_t i = 0; i < links.size(); ++i) {
    out[i] = i > 0 && links[i].parent == static_cast<int>(i) - 1 ? out[i - 1] : static_cast<int>(i);
  }
  return out;
}

}  // namespace

Model::Model(const std::vector<Link>& links, const Vec3<double>& world_gravity,
             std::string model_name)
    : n(checked_size(links, world_gravity, model_name)),
      parent(gather(links, &Link::parent)),
      joint_type(gather(links, &Link::joint_type)),
      axis(gather(links, &Link::axis)),
      X_tree(gather(links, &Link::X_tree)),
      I(gather(links, &Link::I)),
      I_gravcomp(gather(links, &Link::I_gravcomp)),
      q_ref(gather_vector(links, &Link::q_ref)),
      armature(gather_vector(links, &Link::armature)),
      damping(gather_vector(links, &Link::damping)),
      stiffness(gather_vector(links, &Link::stiffness)),
      q_spring(gather_vector(links, &Link::q_spring)),
      friction(gather_vector(links, &Link::friction)),
      friction_velocity(gather_vector(links, &Link::friction_velocity)),
      gravity(world_gravity),
      gravcomp(any_gravcomp(links, world_gravity)),
      actuated_joints(joints_where(links, true)),
      unactuated_joints(joints_where(links, false)),
      joint_names(gather(links, &Link::joint_name)),
      name(std::move(model_name)),
      axis_index(axis_indices(links)),
      run_start(run_starts(links)),
      preorder(depth_first_preorder(links)),
      preorder_index(inverse_permutation(preorder)),
      subtree_size(subtree_sizes(links)) {}

Link Model::link(int i) const {
  Link l;
  l.parent = parent[i];
  l.joint_type = joint_type[i];
  l.axis = axis[i];
  l.X_tree = X_tree[i];
  l.I = I[i];
  l.I_gravcomp = I_gravcomp[i];
  l.q_ref = q_ref[i];
  l.armature = armature[i];
  l.damping = damping[i];
  l.stiffness = stiffness[i];
  l.q_spring = q_spring[i];
  l.friction = friction[i];
  l.friction_velocity = friction_velocity[i];
  l.actuated = !std::binary_search(unactuated_joints.begin(), unactuated_joints.end(), i);
  l.joint_name = joint_names[i];
  return l;
}

Model with_implicit_damping(const Model& model, double dt) {
  if (!(dt >= 0) || !std::isfinite(dt)) {
    throw std::invalid_argument("implicit damping: step must be non-negative and finite, got " + std::to_string(dt));
  }
  std::vector<Link> links;
  links.reserve(static_cast<size_t>(model.n));
  for (int i = 0; i < model.n; ++i) {
    links.push_back(model.link(i));
    links.back().armature += dt * links.back().damping;
  }
  return Model(links, model.gravity, model.name);
}

Model with_joint_friction(const Model& model, const VecX<double>& friction, const VecX<double>& velocity) {
  if (friction.size() != model.n || velocity.size() != model.n) {
    throw std::invalid_argument("joint friction: expected " + std::to_string(model.n) + " values, got " +
                                std::to_string(friction.size()) + " and " + std::to_string(velocity.size()));
  }
  std::vector<Link> links;
  links.reserve(static_cast<size_t>(model.n));
  for (int i = 0; i < model.n; ++i) {
    links.push_back(model.link(i));
    links.back().friction = friction[i];
    links.back().friction_velocity = velocity[i];
  }
  return Model(links, model.gravity, model.name);
}

}  // namespace idmpc
