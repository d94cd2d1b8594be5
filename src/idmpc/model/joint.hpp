#pragma once
/// @file joint.hpp
/// @brief Joint kernels: the joint transform XJ(q)·X_tree of a revolute or prismatic joint, every
/// product with its motion subspace S, and the joint's armature and passive terms. The
/// algorithms touch S, armature, damping and stiffness only through these functions.
///
/// S is represented by (joint_type, axis) alone: S_i = [s_i; 0] for a revolute joint and
/// [0; s_i] for a prismatic one, s_i = model.axis[i] (angular-first).

#include <cmath>

#include "idmpc/model/model.hpp"

namespace idmpc {

/// @brief Parent-to-child transform X_up[i] = XJ(q_i − q_ref_i) · X_tree[i] of link i, written
/// into X (every coefficient, in place: no temporary to copy, whose scattered stores a vector
/// copy right after would have to wait for).
template <typename S> void joint_transform(const Model& model, int i, const S& qi, Transform<S>& X) {
  using std::cos;
  using std::sin;
  const Transform<double>& XT = model.X_tree[i];
  const S d = qi - S(model.q_ref[i]);
  if (model.joint_type[i] == JointType::kPrismatic) {
    // slide by d along s: origin moves, axes stay
    X.E = XT.E.template cast<S>();
    X.r = XT.r.template cast<S>() + XT.E.transpose().template cast<S>() * (model.axis[i].template cast<S>() * d);
    return;
  }
  X.r = XT.r.template cast<S>();
  const int k = model.axis_index[i];
  if (k < 0) {
    // rotation by d about a general axis: coordinates map by Rᵀ
    X.E = axis_rotation<S>(model.axis[i].template cast<S>(), d).transpose() * XT.E.template cast<S>();
    return;
  }
  // rotation about ±e_k mixes only the two other rows of E_tree
  const S angle = d * S(model.axis[i][k]);
  const S c = cos(angle), s = sin(angle);
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  X.E.row(k) = XT.E.row(k).template cast<S>();
  X.E.row(a) = c * XT.E.row(a).template cast<S>() + s * XT.E.row(b).template cast<S>();
  X.E.row(b) = c * XT.E.row(b).template cast<S>() - s * XT.E.row(a).template cast<S>();
}

/// @brief Spatial acceleration of the base: −gravity, so that gravity enters as inertia.
template <typename S> Vec6<S> base_acceleration(const Model& model) {
  Vec6<S> a0 = Vec6<S>::Zero();
  a0.template tail<3>() = -model.gravity.template cast<S>();
  return a0;
}

/// @brief S_i as a dense 6-vector (where a full motion is needed, e.g. to transform it).
template <typename S> Vec6<S> motion_subspace(const Model& model, int i) {
  Vec6<S> s = Vec6<S>::Zero();
  if (model.joint_type[i] == JointType::kRevolute) {
    s.template head<3>() = model.axis[i].template cast<S>();
  } else {
    s.template tail<3>() = model.axis[i].template cast<S>();
  }
  return s;
}

/// @brief S_i in the coordinates of frame 0, given X0 = ^iX_0 (frame 0 → link i): X0⁻¹ S_i,
/// without the products by S's zero half (and none at all for the axis of an axis-aligned hinge).
template <typename S> Vec6<S> motion_subspace_in(const Model& model, int i, const Transform<S>& X0) {
  Vec6<S> out;
  const int k = model.axis_index[i];
  Vec3<S> s;
  if (k >= 0) {
    s = X0.E.row(k).transpose();
    if (model.axis[i][k] < 0) s = -s;
  } else {
    s = X0.E.transpose() * model.axis[i].template cast<S>();
  }
  if (model.joint_type[i] == JointType::kRevolute) {
    out.template head<3>() = s;
    out.template tail<3>() = cross3<S>(X0.r, s);
  } else {
    out.template head<3>().setZero();
    out.template tail<3>() = s;
  }
  return out;
}

/// @brief m += S_i·x: x a joint-space scalar and m a 6-vector, or x a 1×k row and m a 6×k
/// block (k motions at once).
template <typename X, typename Dst>
void add_joint_motion(const Model& model, int i, const X& x, Eigen::MatrixBase<Dst>& m) {
  using S = typename Dst::Scalar;
  const Vec3<S> s = model.axis[i].template cast<S>();
  if (model.joint_type[i] == JointType::kRevolute) {
    m.template topRows<3>().noalias() += s * x;
  } else {
    m.template bottomRows<3>().noalias() += s * x;
  }
}

/// @brief S_iᵀ·f (projection of a force, or of any 6-vector, on joint i's axis).
template <typename S> S joint_project(const Model& model, int i, const Vec6<S>& f) {
  const Vec3<S> s = model.axis[i].template cast<S>();
  return model.joint_type[i] == JointType::kRevolute ? S(s.dot(f.template head<3>()))
                                                     : S(s.dot(f.template tail<3>()));
}

namespace detail {
/// I·σe_K in the angular (revolute) or linear (prismatic) half, K fixed at compile time so that
/// the result can stay in registers (a run-time index would send it through memory).
template <int K, typename S> Vec6<S> inertia_times_axis(const Inertia<S>& I, bool revolute, const S& sg) {
  constexpr int a = (K + 1) % 3, b = (K + 2) % 3;
  Vec6<S> out;
  if (revolute) {
    out.template head<3>() = sg * I.Ibar.col(K);  // Ibar·σe_K
    out[3 + K] = S(0);                             // −h × σe_K
    out[3 + a] = -sg * I.h[b];
    out[3 + b] = sg * I.h[a];
  } else {
    out[K] = S(0);  // h × σe_K
    out[a] = sg * I.h[b];
    out[b] = -sg * I.h[a];
    out.template tail<3>().setZero();
    out[3 + K] = sg * I.m;
  }
  return out;
}
}  // namespace detail

/// @brief I·S_i for a spatial inertia I: the force a unit rate of joint i takes on I.
template <typename S> Vec6<S> inertia_times_motion_subspace(const Model& model, int i,
                                                            const Inertia<S>& I) {
  const int k = model.axis_index[i];
  const bool revolute = model.joint_type[i] == JointType::kRevolute;
  switch (k) {
    case 0: return detail::inertia_times_axis<0, S>(I, revolute, S(model.axis[i][0]));
    case 1: return detail::inertia_times_axis<1, S>(I, revolute, S(model.axis[i][1]));
    case 2: return detail::inertia_times_axis<2, S>(I, revolute, S(model.axis[i][2]));
    default: return I.apply(motion_subspace<S>(model, i));
  }
}

/// @brief out(t, S_iᵀ·F.col(t)) for each column t in [b, e) of a set F of forces.
template <typename S, typename Out>
void project_columns(const Model& model, int i, const SpatialSet<S>& F, int b, int e, Out&& out) {
  const int half = model.joint_type[i] == JointType::kRevolute ? 0 : 3;
  const int k = model.axis_index[i];
  if (k >= 0) {
    const S sg = S(model.axis[i][k]);
    const S* f = F.row(half + k).data();
    for (int t = b; t < e; ++t) out(t, sg * f[t]);
    return;
  }
  const S s0 = S(model.axis[i][0]), s1 = S(model.axis[i][1]), s2 = S(model.axis[i][2]);
  const S* f0 = F.row(half).data();
  const S* f1 = F.row(half + 1).data();
  const S* f2 = F.row(half + 2).data();
  for (int t = b; t < e; ++t) out(t, s0 * f0[t] + s1 * f1[t] + s2 * f2[t]);
}

/// @brief row −= S_iᵀ·F for a 6×k block F (k projections at once; row is 1×k).
template <typename Row, typename F>
void subtract_joint_projection(const Model& model, int i, const Eigen::MatrixBase<F>& Fm,
                               Eigen::MatrixBase<Row>& row) {
  using S = typename F::Scalar;
  const Vec3<S> s = model.axis[i].template cast<S>();
  if (model.joint_type[i] == JointType::kRevolute) {
    row.noalias() -= s.transpose() * Fm.template topRows<3>();
  } else {
    row.noalias() -= s.transpose() * Fm.template bottomRows<3>();
  }
}

/// @brief M·S_i for a 6×6 matrix M (e.g. U = IA·S of the articulated-body algorithm).
template <typename S> Vec6<S> times_motion_subspace(const Model& model, int i, const Mat6<S>& M) {
  const Vec3<S> s = model.axis[i].template cast<S>();
  return model.joint_type[i] == JointType::kRevolute ? Vec6<S>(M.template leftCols<3>() * s)
                                                     : Vec6<S>(M.template rightCols<3>() * s);
}

/// @brief The partial derivatives of armature_and_passive with respect to q, v and a, without
/// the friction's (friction_slope, which depends on v).
struct ArmaturePassivePartials {
  double dq;  ///< stiffness k
  double dv;  ///< damping d
  double da;  ///< armature
};

/// @brief Joint friction f·tanh(v/ε): a smooth stand-in for MuJoCo's friction loss, which is a
/// dry-friction constraint force of magnitude ≤ f (formulations.md §Passive forces). Zero where f = 0.
template <typename S> S joint_friction(const Model& model, int i, const S& v) {
  using std::tanh;
  const double f = model.friction[i];
  if (f == 0) return S(0);
  return f * tanh(v * (1.0 / model.friction_velocity[i]));
}

/// @brief ∂/∂v of joint_friction: (f/ε)·(1 − tanh²(v/ε)).
template <typename S> S friction_slope(const Model& model, int i, const S& v) {
  using std::tanh;
  const double f = model.friction[i];
  if (f == 0) return S(0);
  const double inv_eps = 1.0 / model.friction_velocity[i];
  const S t = tanh(v * inv_eps);
  return (f * inv_eps) * (S(1) - t * t);
}

/// @brief Joint i's own terms of ID(q, v, a)_i besides the bodies' (formulations.md §The model, §Passive forces):
/// armature·a + d·v + k·(q − q_spring) + f·tanh(v/ε), i.e. the armature's inertia minus
/// MuJoCo's passive force −d·v − k·(q − q_spring) and the smooth friction. Linear in (q, v, a)
/// but for the friction: its partials are armature_passive_partials plus friction_slope in v.
/// FD (ABA) uses it with a = 0 and the armature in D.
template <typename S>
S armature_and_passive(const Model& model, int i, const S& q, const S& v, const S& a) {
  return model.armature[i] * a + model.damping[i] * v + model.stiffness[i] * (q - model.q_spring[i]) +
         joint_friction<S>(model, i, v);
}

/// @brief ∂/∂q, ∂/∂v, ∂/∂a of armature_and_passive(model, i, q, v, a) without the friction:
/// (k, d, armature).
inline ArmaturePassivePartials armature_passive_partials(const Model& model, int i) {
  return {model.stiffness[i], model.damping[i], model.armature[i]};
}

}  // namespace idmpc
