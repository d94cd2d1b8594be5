#pragma once
/// @file kinematics.hpp
/// @brief Frame kinematics: the world placement of a frame rigidly attached to a link (a MuJoCo
/// site or body) and its world-aligned Jacobian, as MuJoCo's site_xpos/site_xmat and
/// mj_jacSite, walking only the frame's ancestors.

#include <algorithm>
#include <vector>

#include "idmpc/model/checks.hpp"
#include "idmpc/model/frame.hpp"
#include "idmpc/model/joint.hpp"

namespace idmpc {

/// @brief Placement and Jacobian of one Frame, for scalar S = double or Pack<W> (each lane its
/// own q). Holds the frame's ancestor path and one 6-vector per ancestor; allocates nothing
/// after construction.
///
/// Conventions: p is the frame's origin in world coordinates; R (world ← frame) has the frame's
/// axes in world coordinates as its columns (MuJoCo's site_xmat, row-major there). The Jacobian
/// is world-aligned with the translational rows first, as MuJoCo's [jacp; jacr]: q̇ ↦ [ṗ; ω],
/// ω the frame's angular velocity in world coordinates.
template <typename S> class FrameKinematics {
 public:
  using Jacobian = Eigen::Matrix<S, 6, Eigen::Dynamic>;

  /// @brief Stores the ancestors of frame.link (root → link) and sizes the buffers. Throws
  /// std::invalid_argument (check_frame) if the frame does not fit the model.
  FrameKinematics(const Model& model, const Frame& frame)
      : n_(model.n), link_(frame.link), placement_(cast_transform(frame.placement)) {
    check_frame(model, frame);
    for (int i = frame.link; i >= 0; i = model.parent[i]) path_.push_back(i);
    std::reverse(path_.begin(), path_.end());
    S_W_.resize(path_.size());
  }

  /// @brief World placement of the frame at joint positions q (size n; `model` is the one the
  /// workspace was made for), read back through position() and rotation(). Also keeps each
  /// ancestor's motion subspace in world coordinates, which jacobian() and
  /// add_jacobian_transpose_times() read: call compute first.
  template <typename Q> void compute(const Model& model, const Eigen::MatrixBase<Q>& q) {
    IDMPC_CHECK_ARGUMENT(model.n == n_ && q.size() == n_, "FrameKinematics::compute: q must have size model.n");
    // world → link down the ancestor path, S_j in world coordinates (at the world origin)
    Transform<S> X0, X_up;
    for (std::size_t k = 0; k < path_.size(); ++k) {
      const int i = path_[k];
      joint_transform<S>(model, i, S(q[i]), X_up);
      X0 = k == 0 ? X_up : X_up * X0;
      S_W_[k] = motion_subspace_in<S>(model, i, X0);
    }
    // world → frame: p is its origin, R = Eᵀ its axes in world coordinates
    const Transform<S> X_frame = placement_ * X0;
    p_ = X_frame.r;
    R_ = X_frame.E.transpose();
  }

  /// @brief Frame origin in world coordinates (after compute).
  const Vec3<S>& position() const { return p_; }
  /// @brief World ← frame rotation: columns are the frame's axes in world coordinates.
  const Mat3<S>& rotation() const { return R_; }

  /// @brief The 6×n world-aligned Jacobian into J (every coefficient written; J has n columns):
  /// rows 0–2 translational, ∂p/∂q (MuJoCo's jacp), rows 3–5 rotational, the frame's angular
  /// velocity in world coordinates per q̇ (MuJoCo's jacr). Columns of non-ancestors are zero.
  /// For ancestor j with world axis ω_j through o_j: [ω_j × (p − o_j); ω_j] if revolute, [ω_j; 0]
  /// if prismatic; both are S_j (world coordinates, at the origin) moved to the point p.
  void jacobian(Eigen::Ref<Jacobian> J) const {
    IDMPC_CHECK_ARGUMENT(J.cols() == n_, "FrameKinematics::jacobian: J must have model.n columns");
    J.setZero();
    for (std::size_t k = 0; k < path_.size(); ++k) {
      const Vec6<S>& s = S_W_[k];
      const auto w = s.template head<3>();
      J.col(path_[k]).template head<3>() = s.template tail<3>() + cross3<S>(w, p_);
      J.col(path_[k]).template tail<3>() = w;
    }
  }

  /// @brief g += Jᵀ [f_lin; f_ang] in O(depth), without forming J (g has size n): for an
  /// ancestor revolute joint j, g_j += ω_j·(f_ang + (p − o_j) × f_lin); prismatic:
  /// g_j += ω_j·f_lin. The force f_lin at p with the couple f_ang is moved to the world origin
  /// once, F = [f_ang + p × f_lin; f_lin], and g_j += S_jᵀF.
  void add_jacobian_transpose_times(const Vec3<S>& f_lin, const Vec3<S>& f_ang, Eigen::Ref<VecX<S>> g) const {
    IDMPC_CHECK_ARGUMENT(g.size() == n_, "FrameKinematics::add_jacobian_transpose_times: g must have size model.n");
    const Vec3<S> n0 = f_ang + cross3<S>(p_, f_lin);
    for (std::size_t k = 0; k < path_.size(); ++k) {
      const Vec6<S>& s = S_W_[k];
      g[path_[k]] += s.template head<3>().dot(n0) + s.template tail<3>().dot(f_lin);
    }
  }

  /// @brief The link the frame moves with (−1: the base).
  int link() const { return link_; }
  /// @brief The frame's ancestor links, root first, ending at link() (empty on the base).
  const std::vector<int>& path() const { return path_; }

 private:
  static Transform<S> cast_transform(const Transform<double>& X) {
    Transform<S> out;
    out.E = X.E.template cast<S>();
    out.r = X.r.template cast<S>();
    return out;
  }

  int n_;
  int link_;
  Transform<S> placement_;
  std::vector<int> path_;
  std::vector<Vec6<S>> S_W_;  // S_j of each ancestor on path_, world coordinates
  Vec3<S> p_ = Vec3<S>::Zero();
  Mat3<S> R_ = Mat3<S>::Identity();
};

/// @brief The world placement of `frame` at joint positions q (size n): its origin p and its
/// rotation R (world ← frame), as FrameKinematics::compute gives them, without a workspace: the
/// ancestors are composed from the frame's link up to the root. Reads only its arguments, so
/// concurrent calls are safe; allocation-free. For the pose alone (no Jacobian).
template <typename S, typename Q>
void frame_pose(const Model& model, const Frame& frame, const Eigen::MatrixBase<Q>& q, Vec3<S>& p, Mat3<S>& R) {
  IDMPC_CHECK_ARGUMENT(q.size() == model.n, "frame_pose: q must have size model.n");
  // world → link: X_up of the link, then of each ancestor in turn (composed on the right)
  Transform<S> X0, X_up;
  for (int i = frame.link; i >= 0; i = model.parent[i]) {
    joint_transform<S>(model, i, S(q[i]), X_up);
    X0 = X0 * X_up;
  }
  Transform<S> placement;
  placement.E = frame.placement.E.template cast<S>();
  placement.r = frame.placement.r.template cast<S>();
  const Transform<S> X_frame = placement * X0;
  p = X_frame.r;
  R = X_frame.E.transpose();
}

}  // namespace idmpc
