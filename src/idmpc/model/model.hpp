#pragma once
/// @file model.hpp
/// @brief Immutable kinematic tree of 1-DoF joints (one link per dof), in topological order.

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

enum class JointType { kRevolute, kPrismatic };

/// @brief The rigid-body model the controllers use. Built once (e.g. by the MuJoCo importer),
/// then const. Link i carries joint i; parent[i] < i, −1 for the fixed base.
///
/// Link i's frame has its origin on joint i's axis; X_tree[i] maps the parent link's frame to
/// link i's frame at zero joint displacement; the joint then rotates about (or slides along)
/// axis[i] through that origin by q_i − q_ref[i].
struct Model {
  int n = 0;                                    ///< number of links = dofs
  std::vector<int> parent;                      ///< size n, −1 for the base
  std::vector<JointType> joint_type;            ///< size n
  std::vector<Vec3<double>> axis;               ///< unit joint axis in the link frame
  std::vector<Vec6<double>> S;                  ///< motion subspace in the link frame
  std::vector<Transform<double>> X_tree;        ///< parent link frame → link frame at q = q_ref
  std::vector<Inertia<double>> I;               ///< link inertia (welded bodies merged)
  VecX<double> q_ref;                           ///< joint reference (MuJoCo qpos0)
  VecX<double> armature;                        ///< added to diag(M)
  VecX<double> damping;                         ///< passive −d·v
  VecX<double> stiffness;                       ///< passive −k·(q − q_spring)
  VecX<double> q_spring;
  Vec3<double> gravity = Vec3<double>(0, 0, -9.81);  ///< world gravity (zero if disabled)
  std::vector<std::string> joint_names;         ///< for messages
  std::vector<int> subtree_end;                 ///< subtree of i is [i, subtree_end[i])
  std::vector<int> axis_index;                  ///< 0/1/2 if axis[i] = ±e_k, else −1
  std::vector<double> axis_sign;                ///< ±1 for an axis-aligned joint
  std::string name;

  /// @brief Checks sizes and topology; fills S and subtree_end. Throws std::invalid_argument.
  void finalize() {
    const auto un = static_cast<size_t>(n);
    if (n < 1) throw std::invalid_argument("model has no degrees of freedom");
    if (parent.size() != un || joint_type.size() != un || axis.size() != un ||
        X_tree.size() != un || I.size() != un || q_ref.size() != n || armature.size() != n ||
        damping.size() != n || stiffness.size() != n || q_spring.size() != n) {
      throw std::invalid_argument("model arrays do not all have size n = " + std::to_string(n));
    }
    if (joint_names.size() != un) joint_names.resize(un);
    S.assign(un, Vec6<double>::Zero());
    axis_index.assign(un, -1);
    axis_sign.assign(un, 1.0);
    subtree_end.assign(un, 0);
    for (int i = 0; i < n; ++i) {
      if (parent[i] >= i || parent[i] < -1) {
        throw std::invalid_argument("link " + std::to_string(i) +
                                    " is not in topological order (parent " +
                                    std::to_string(parent[i]) + ")");
      }
      for (int k = 0; k < 3; ++k) {
        if (std::abs(axis[i][k]) == 1.0) {
          axis_index[i] = k;
          axis_sign[i] = axis[i][k];
        }
      }
      if (joint_type[i] == JointType::kRevolute) {
        S[i].head<3>() = axis[i];
      } else {
        S[i].tail<3>() = axis[i];
      }
    }
    // a subtree is contiguous in depth-first order: it ends at the next non-descendant
    for (int i = n - 1; i >= 0; --i) {
      int end = i + 1;
      while (end < n && is_ancestor(i, end)) end = subtree_end[end];
      subtree_end[i] = end;
    }
    for (int i = 0; i < n; ++i) {
      for (int k = i + 1; k < subtree_end[i]; ++k) {
        if (!is_ancestor(i, k)) {
          throw std::invalid_argument("links are not in depth-first order");
        }
      }
    }
  }

  /// @brief True if a is an ancestor of (or equal to) b.
  bool is_ancestor(int a, int b) const {
    while (b > a) b = parent[b];
    return b == a;
  }
};

}  // namespace idmpc
