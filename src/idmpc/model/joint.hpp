#pragma once
/// @file joint.hpp
/// @brief Joint kernels: the joint transform XJ(q)·X_tree of a revolute or prismatic joint and
/// products with the (sparse) motion subspace S.

#include <cmath>

#include "idmpc/model/model.hpp"

namespace idmpc {

/// @brief Parent-to-child transform X_up[i] = XJ(q_i − q_ref_i) · X_tree[i] of link i.
template <typename S> Transform<S> joint_transform(const Model& model, int i, const S& qi) {
  using std::cos;
  using std::sin;
  const Transform<double>& XT = model.X_tree[i];
  const S d = qi - S(model.q_ref[i]);
  Transform<S> X;
  if (model.joint_type[i] == JointType::kPrismatic) {
    // slide by d along s: origin moves, axes stay
    X.E = XT.E.template cast<S>();
    X.r = XT.r.template cast<S>() + XT.E.transpose().template cast<S>() * (model.axis[i].template cast<S>() * d);
    return X;
  }
  X.r = XT.r.template cast<S>();
  const int k = model.axis_index[i];
  if (k < 0) {
    // rotation by d about a general axis: coordinates map by Rᵀ
    X.E = axis_rotation<S>(model.axis[i].template cast<S>(), d).transpose() * XT.E.template cast<S>();
    return X;
  }
  // rotation about ±e_k mixes only the two other rows of E_tree
  const S angle = d * S(model.axis_sign[i]);
  const S c = cos(angle), s = sin(angle);
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  X.E.row(k) = XT.E.row(k).template cast<S>();
  X.E.row(a) = c * XT.E.row(a).template cast<S>() + s * XT.E.row(b).template cast<S>();
  X.E.row(b) = c * XT.E.row(b).template cast<S>() - s * XT.E.row(a).template cast<S>();
  return X;
}

/// @brief Spatial acceleration of the base: −gravity, so that gravity enters as inertia.
template <typename S> Vec6<S> base_acceleration(const Model& model) {
  Vec6<S> a0 = Vec6<S>::Zero();
  a0.template tail<3>() = -model.gravity.template cast<S>();
  return a0;
}

/// @brief m += S_i·x (motion subspace of joint i times a joint-space scalar).
template <typename S> void add_joint_motion(const Model& model, int i, const S& x, Vec6<S>& m) {
  const auto s = model.axis[i].template cast<S>();
  if (model.joint_type[i] == JointType::kRevolute) {
    m.template head<3>() += s * x;
  } else {
    m.template tail<3>() += s * x;
  }
}

/// @brief S_iᵀ·f (projection of a force, or of any 6-vector, on joint i's axis).
template <typename S> S joint_project(const Model& model, int i, const Vec6<S>& f) {
  const auto s = model.axis[i].template cast<S>();
  return model.joint_type[i] == JointType::kRevolute ? S(s.dot(f.template head<3>()))
                                                     : S(s.dot(f.template tail<3>()));
}

}  // namespace idmpc
