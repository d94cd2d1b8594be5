#include "idmpc/ocp/stage_terms.hpp"

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "idmpc/dynamics/rnea.hpp"

namespace idmpc {
namespace {

const Model& checked(const std::shared_ptr<const Model>& model) {
  if (!model) throw std::invalid_argument("optimal control problem: expected a model, got none");
  return *model;
}

// the limits with the passive joints unbounded: no actuator, no torque to limit
TorqueLimits actuated_limits(const Model& model, TorqueLimits limits) {
  if (limits.lower.size() != model.n || limits.upper.size() != model.n) return limits;  // TorqueBounds says why
  for (int j : model.unactuated_joints) {
    limits.lower[j] = -std::numeric_limits<double>::infinity();
    limits.upper[j] = std::numeric_limits<double>::infinity();
  }
  return limits;
}

// the mean R of the actuated joints, or 1
double passive_scale_of(const Model& model, const VecX<double>& R) {
  if (model.n_actuated() == 0 || R.size() != model.n) return 1;
  double sum = 0;
  for (int j : model.actuated_joints) sum += R[j];
  return sum > 0 ? sum / model.n_actuated() : 1;
}

std::string frame_label(const Frame& frame) { return "frame target '" + frame.name + "'"; }

// a fresh id for each frame target set, so that a FrameScratch knows whether it fits
std::uint64_t next_frame_id() {
  static std::atomic<std::uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

// a target pose: a finite position and a rotation matrix
void check_pose(const Frame& frame, const Vec3<double>& position, const Mat3<double>& rotation) {
  if (!position.allFinite()) throw std::invalid_argument(frame_label(frame) + ": position is not finite");
  if (!rotation.allFinite() || !(rotation.transpose() * rotation).isIdentity(1e-9) || rotation.determinant() < 0) {
    throw std::invalid_argument(frame_label(frame) + ": rotation is not a rotation matrix");
  }
}

}  // namespace

StageTerms::StageTerms(std::shared_ptr<const Model> model, QuadraticCost cost, const TorqueLimits& limits, int N,
                       bool frame_jacobian_matrix, bool passive_constraints)
    : model_(std::move(model)),
      cost_(std::move(cost)),
      bounds_(actuated_limits(checked(model_), limits), cost_.weights().R, cost_.n()),
      passive_constraints_(passive_constraints),
      passive_(model_->unactuated_joints),
      passive_scale_(passive_scale_of(*model_, cost_.weights().R)),
      N_(N),
      frame_jacobian_matrix_(frame_jacobian_matrix),
      d_hat_(Vec::Zero(checked(model_).n)),
      zero_(Vec::Zero(model_->n)),
      rnea_data_(*model_, DataParts::rnea()) {
  if (cost_.n() != model_->n) {
    throw std::invalid_argument("the costs have " + std::to_string(cost_.n()) + " joints, the model " +
                                std::to_string(model_->n));
  }
  if (N < 1) throw std::invalid_argument("horizon steps N must be at least 1, got " + std::to_string(N));
  for (MatX<double>* x : {&q_ref_, &v_ref_, &u_ref_}) *x = MatX<double>::Zero(model_->n, N + 1);
  update_joint_references();
}

void StageTerms::set_passive_scale(double s) {
  if (!(s > 0) || !std::isfinite(s)) {
    throw std::invalid_argument("the passive torques' row scale must be positive and finite, got " + std::to_string(s));
  }
  passive_scale_ = s;
}

StageTerms::StageTerms(const StageTerms& o)
    : model_(o.model_),
      cost_(o.cost_),
      bounds_(o.bounds_),
      passive_constraints_(o.passive_constraints_),
      passive_(o.passive_),
      passive_scale_(o.passive_scale_),
      N_(o.N_),
      frame_jacobian_matrix_(o.frame_jacobian_matrix_),
      d_hat_(o.d_hat_),
      zero_(o.zero_),
      q_ref_(o.q_ref_),
      v_ref_(o.v_ref_),
      u_ref_(o.u_ref_),
      rnea_data_(*o.model_, DataParts::rnea()),
      joint_trajectory_(o.joint_trajectory_),
      frame_trajectory_(o.frame_trajectory_),
      t0_(o.t0_),
      dtau_(o.dtau_),
      sampled_(o.sampled_),
      terminal_P_(o.terminal_P_),
      frame_(o.frame_),
      frame_id_(o.frame_id_),
      p_ref_(o.p_ref_) {}

StageTerms& StageTerms::operator=(const StageTerms& o) {
  if (this != &o) {
    StageTerms copy(o);
    *this = std::move(copy);
  }
  return *this;
}

void StageTerms::set_disturbance(const Vec& d_hat) {
  if (d_hat.size() != n() || !d_hat.allFinite()) {
    throw std::invalid_argument("disturbance estimate: expected " + std::to_string(n()) + " finite values, got " +
                                std::to_string(d_hat.size()));
  }
  d_hat_ = d_hat;
  update_joint_references();
}

void StageTerms::set_target(const Vec& q_ref) {
  cost_.set_target(q_ref);
  joint_trajectory_.reset();
  update_joint_references();
}

void StageTerms::set_joint_trajectory(std::shared_ptr<const Trajectory> q_ref) {
  if (q_ref && q_ref->dim() != n()) {
    throw std::invalid_argument("joint reference '" + q_ref->describe() + "' has " + std::to_string(q_ref->dim()) +
                                " values, expected " + std::to_string(n()) + " (one per joint)");
  }
  joint_trajectory_ = std::move(q_ref);
  sampled_ = false;
  update_joint_references();
}

void StageTerms::set_frame_target(std::optional<FrameTarget> target) {
  frame_trajectory_.reset();
  sampled_ = false;
  if (!target) {
    frame_.reset();
    frame_id_ = 0;
    return;
  }
  const FrameTarget& f = *target;
  check_frame(*model_, f.frame);  // its link and placement
  if (!f.position_weight.allFinite() || (f.position_weight.array() < 0).any() ||
      !std::isfinite(f.orientation_weight) || f.orientation_weight < 0) {
    throw std::invalid_argument(frame_label(f.frame) + ": weights must be finite and non-negative");
  }
  check_pose(f.frame, f.position, f.rotation);
  frame_ = target;
  frame_id_ = next_frame_id();
  p_ref_ = frame_->position.replicate(1, N_ + 1);
}

void StageTerms::set_terminal_weight(const MatX<double>& P) {
  const int n2 = 2 * n();
  if (P.size() == 0) {
    terminal_P_.resize(0, 0);
    return;
  }
  if (P.rows() != n2 || P.cols() != n2 || !P.allFinite() || !P.isApprox(P.transpose(), 1e-12)) {
    throw std::invalid_argument("terminal weight: expected a finite symmetric " + std::to_string(n2) + " x " +
                                std::to_string(n2) + " matrix, got " + std::to_string(P.rows()) + " x " +
                                std::to_string(P.cols()));
  }
  terminal_P_ = P;
}

void StageTerms::set_frame_trajectory(std::shared_ptr<const Trajectory> p_ref) {
  if (p_ref && !frame_) {
    throw std::invalid_argument("frame reference '" + p_ref->describe() + "': the problem has no frame target");
  }
  if (p_ref && p_ref->dim() != 3) {
    throw std::invalid_argument("frame reference '" + p_ref->describe() + "' has " + std::to_string(p_ref->dim()) +
                                " values, expected 3 (a position)");
  }
  frame_trajectory_ = std::move(p_ref);
  sampled_ = false;
  update_frame_references();
}

void StageTerms::set_frame_pose(const Vec3<double>& position, const Mat3<double>& rotation) {
  if (!frame_) throw std::invalid_argument("set_frame_pose: the problem has no frame target");
  check_pose(frame_->frame, position, rotation);
  frame_->position = position;
  frame_->rotation = rotation;
  if (!frame_trajectory_) update_frame_references();
}

void StageTerms::set_stage_times(double t0, double dtau) {
  if (!moving() || (sampled_ && t0 == t0_ && dtau == dtau_)) return;
  t0_ = t0;
  dtau_ = dtau;
  sampled_ = true;
  if (joint_trajectory_) update_joint_references();
  if (frame_trajectory_) update_frame_references();
}

void StageTerms::update_joint_references() {
  // the gravity and spring torque that holds each stage's target, less what the model misses
  // (formulations.md §Torque reference); a fixed target is one RNEA, copied to every stage
  if (joint_trajectory_) {
    if (!sampled_) return;  // until set_stage_times
    for (int i = 0; i <= N_; ++i) {
      joint_trajectory_->sample(t0_ + i * dtau_, q_ref_.col(i), v_ref_.col(i));
      u_ref_.col(i) = rnea(*model_, rnea_data_, q_ref_.col(i), zero_, zero_) - d_hat_;
    }
    return;
  }
  u_ref_.col(0) = rnea(*model_, rnea_data_, cost_.q_ref(), zero_, zero_) - d_hat_;
  for (int i = 0; i <= N_; ++i) {
    q_ref_.col(i) = cost_.q_ref();
    v_ref_.col(i).setZero();
    u_ref_.col(i) = u_ref_.col(0);
  }
}

void StageTerms::update_frame_references() {
  if (!frame_) return;
  if (!frame_trajectory_) {
    for (int i = 0; i <= N_; ++i) p_ref_.col(i) = frame_->position;
    return;
  }
  if (!sampled_) return;
  for (int i = 0; i <= N_; ++i) {
    frame_trajectory_->sample(t0_ + i * dtau_, sample3_, rate3_);
    p_ref_.col(i) = sample3_;
  }
}

double StageTerms::cost_against(In q, In v, In u, In q_ref, In v_ref, In u_ref, const Vec3<double>& p_ref) const {
  const OcpWeights& w = cost_.weights();
  auto quadratic = [](const auto& e, const auto& W) { return 0.5 * e.dot(W.cwiseProduct(e)); };  // W: VecX or Vec3, no copy
  const double L = quadratic(q - q_ref, w.Qq) + quadratic(v - v_ref, w.Qv) + quadratic(u - u_ref, w.R);
  if (!frame_) return L;
  // the frame's pose without a workspace: this stays const for concurrent callers
  Vec3<double> p;
  Mat3<double> R;
  frame_pose(*model_, frame_->frame, q, p, R);
  const Vec3<double> e = p - p_ref;
  // w_o(1 − cos θ), cos θ = (tr(R_refᵀR) − 1)/2
  const double cos_theta = 0.5 * ((frame_->rotation.transpose() * R).trace() - 1);
  return L + quadratic(e, frame_->position_weight) + frame_->orientation_weight * (1 - cos_theta);
}

double StageTerms::stage_cost(int i, In q, In v, In u) const {
  return cost_against(q, v, u, q_ref_.col(i), v_ref_.col(i), u_ref_.col(i),
                      frame_ ? Vec3<double>(p_ref_.col(i)) : Vec3<double>::Zero());
}

double StageTerms::terminal_cost(In q, In v) const {
  const int i = N_;
  if (terminal_P_.size() == 0) return stage_cost(i, q, v, u_ref_.col(i));
  const int n = this->n();
  double sum = 0;
  for (int r = 0; r < 2 * n; ++r) {
    const double er = r < n ? q[r] - q_ref_(r, i) : v[r - n] - v_ref_(r - n, i);
    for (int c = 0; c < 2 * n; ++c) {
      const double ec = c < n ? q[c] - q_ref_(c, i) : v[c - n] - v_ref_(c - n, i);
      sum += er * terminal_P_(r, c) * ec;
    }
  }
  // the frame term alone: the joint terms measured against the state itself vanish
  const double frame = frame_ ? cost_against(q, v, u_ref_.col(i), q, v, u_ref_.col(i), Vec3<double>(p_ref_.col(i))) : 0.0;
  return 0.5 * sum + frame;
}

StageTerms::CostScratch StageTerms::cost_scratch() const {
  const int n = this->n();
  return CostScratch{Vec::Zero(n), Vec::Zero(n), Vec::Zero(n), Vec::Zero(n), Data(*model_, DataParts::rnea()),
                     Vec3<double>::Zero(), Vec3<double>::Zero()};
}

double StageTerms::stage_cost_at(double t, In q, In v, In u, CostScratch& s) const {
  IDMPC_CHECK_ARGUMENT(s.q_ref.size() == n() && s.data.n == n(),
                       "StageTerms::stage_cost_at: the scratch is not this problem's (cost_scratch())");
  if (joint_trajectory_) {
    joint_trajectory_->sample(t, s.q_ref, s.v_ref);
    s.u_ref = rnea(*model_, s.data, s.q_ref, s.zero, s.zero) - d_hat_;
  } else {
    // a fixed target: the same references at every time
    s.q_ref = q_ref_.col(0);
    s.v_ref = v_ref_.col(0);
    s.u_ref = u_ref_.col(0);
  }
  s.p_ref.setZero();
  if (frame_) {
    if (frame_trajectory_) {
      frame_trajectory_->sample(t, s.p_ref, s.rate3);
    } else {
      s.p_ref = frame_->position;
    }
  }
  return cost_against(q, v, u, s.q_ref, s.v_ref, s.u_ref, s.p_ref);
}

template <typename S>
void StageTerms::state_gradient_of(int i, RefIn<S> q, RefIn<S> v, RefOut<S> L_q, RefOut<S> L_v,
                                   FrameScratch<S>& scratch) const {
  const VecX<double>& Qq = cost_.weights().Qq;
  const VecX<double>& Qv = cost_.weights().Qv;
  if (i == N_ && terminal_P_.size() > 0) {
    // P e, e = (q − q_ref, v − v_ref), row by row (P is double, e may be dual)
    const int n = this->n();
    for (int r = 0; r < 2 * n; ++r) {
      S sum = S(0.0);
      for (int c = 0; c < n; ++c) {
        sum += terminal_P_(r, c) * (q[c] - q_ref_(c, i));
        sum += terminal_P_(r, n + c) * (v[c] - v_ref_(c, i));
      }
      (r < n ? L_q[r] : L_v[r - n]) = sum;
    }
  } else {
    L_q = Qq.cwiseProduct(q - q_ref_.col(i));
    L_v = Qv.cwiseProduct(v - v_ref_.col(i));
  }
  if (!frame_) return;
  // Jᵀf with f_lin = w_p∘(p − p_ref), f_ang = ½w_o vee(A − Aᵀ), A = R R_refᵀ (cost.hpp)
  if (scratch.frame_id != frame_id_) {
    // sized for this frame target once (the first evaluation after set_frame_target)
    scratch.kinematics.emplace(*model_, frame_->frame);
    scratch.jacobian = Eigen::Matrix<S, 6, Eigen::Dynamic>::Zero(6, n());
    scratch.frame_id = frame_id_;
  }
  FrameKinematics<S>& fk = *scratch.kinematics;
  fk.compute(*model_, q);
  const Vec3<S> f_lin = frame_->position_weight.cwiseProduct(fk.position() - p_ref_.col(i));
  const Mat3<S> A = fk.rotation() * frame_->rotation.transpose();
  const Vec3<S> f_ang =
      (0.5 * frame_->orientation_weight) * Vec3<S>(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
  if (frame_jacobian_matrix_) {
    fk.jacobian(scratch.jacobian);
    L_q.noalias() += scratch.jacobian.template topRows<3>().transpose() * f_lin;
    L_q.noalias() += scratch.jacobian.template bottomRows<3>().transpose() * f_ang;
  } else {
    fk.add_jacobian_transpose_times(f_lin, f_ang, L_q);
  }
}

void StageTerms::state_gradient(int i, In q, In v, Out L_q, Out L_v, FrameScratch<double>& frame) const {
  state_gradient_of<double>(i, q, v, L_q, L_v, frame);
}

void StageTerms::state_gradient(int i, DualIn q, DualIn v, DualOut L_q, DualOut L_v,
                                FrameScratch<Dual>& frame) const {
  state_gradient_of<Dual>(i, q, v, L_q, L_v, frame);
}

}  // namespace idmpc

namespace idmpc {

void StageTerms::state_hessian(int i, In q, Eigen::Ref<MatX<double>> H_qq, Out H_vv,
                               FrameScratch<double>& scratch) const {
  // the weights and the target's orientation are the same at every stage
  if (i == N_ && terminal_P_.size() > 0) {
    throw std::logic_error("the terminal weight matrix has no Gauss-Newton Hessian here (C/GMRES only)");
  }
  const OcpWeights& w = cost_.weights();
  H_qq.setZero();
  H_qq.diagonal() = w.Qq;
  H_vv = w.Qv;
  if (!frame_) return;
  if (scratch.frame_id != frame_id_) {
    scratch.kinematics.emplace(*model_, frame_->frame);
    scratch.jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, n());
    scratch.frame_id = frame_id_;
  }
  FrameKinematics<double>& fk = *scratch.kinematics;
  fk.compute(*model_, q);
  fk.jacobian(scratch.jacobian);
  const auto Jp = scratch.jacobian.topRows<3>();
  const auto Jw = scratch.jacobian.bottomRows<3>();
  // w_o(1 − cos θ) = w_o(1 − (tr E − 1)/2) with E = R R_refᵀ; turning the frame by exp([δ]×)
  // gives tr(exp([δ]×)E), whose second-order term is ½δᵀ(E_sym − tr(E) I)δ
  Mat3<double> H_psd = Mat3<double>::Zero();
  if (frame_->orientation_weight > 0) {
    const Mat3<double> E = fk.rotation() * frame_->rotation.transpose();
    const Mat3<double> H =
        (0.5 * frame_->orientation_weight) * (E.trace() * Mat3<double>::Identity() - 0.5 * (E + E.transpose()));
    Eigen::SelfAdjointEigenSolver<Mat3<double>> eig(H);
    H_psd = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  }
  // column by column through fixed-size 3-vectors: no temporaries
  for (Eigen::Index c = 0; c < H_qq.cols(); ++c) {
    const Vec3<double> tp = frame_->position_weight.cwiseProduct(Jp.col(c));
    const Vec3<double> tw = H_psd * Jw.col(c);
    H_qq.col(c).noalias() += Jp.transpose() * tp;
    H_qq.col(c).noalias() += Jw.transpose() * tw;
  }
}

}  // namespace idmpc
