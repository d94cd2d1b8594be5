#pragma once
/// @file joint.hpp
/// @brief Joint kernels: the joint transform XJ(q) of a revolute or prismatic joint.

#include "idmpc/model/model.hpp"

namespace idmpc {

/// @brief Parent-to-child transform X_up[i] = XJ(q_i − q_ref_i) · X_tree[i] of link i.
template <typename S> Transform<S> joint_transform(const Model& model, int i, const S& qi) {
  const S d = qi - S(model.q_ref[i]);
  const Vec3<S> s = model.axis[i].template cast<S>();
  Transform<S> XJ;
  if (model.joint_type[i] == JointType::kRevolute) {
    // rotation by d about s: coordinates map by Rᵀ
    XJ.E = axis_rotation<S>(s, d).transpose();
  } else {
    XJ.r = s * d;
  }
  Transform<S> XT;
  XT.E = model.X_tree[i].E.template cast<S>();
  XT.r = model.X_tree[i].r.template cast<S>();
  return XJ * XT;
}

/// @brief Spatial acceleration of the base: −gravity, so that gravity enters as inertia.
template <typename S> Vec6<S> base_acceleration(const Model& model) {
  Vec6<S> a0 = Vec6<S>::Zero();
  a0.template tail<3>() = -model.gravity.template cast<S>();
  return a0;
}

}  // namespace idmpc
