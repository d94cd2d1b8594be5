#include "idmpc/ocp/problem.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>

#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {

std::string to_string(Formulation f) { return f == Formulation::kForwardDynamics ? "fd" : "id"; }
std::string to_string(DerivativeMode d) { return d == DerivativeMode::kMatrix ? "matrix" : "adjoint"; }

Formulation parse_formulation(const std::string& s) {
  if (s == "fd") return Formulation::kForwardDynamics;
  if (s == "id") return Formulation::kInverseDynamics;
  throw std::invalid_argument("unknown formulation '" + s + "': expected 'fd' or 'id'");
}

DerivativeMode parse_derivative_mode(const std::string& s) {
  if (s == "matrix") return DerivativeMode::kMatrix;
  if (s == "adjoint") return DerivativeMode::kAdjoint;
  throw std::invalid_argument("unknown derivative mode '" + s + "': expected 'matrix' or 'adjoint'");
}

OcpProblem::OcpProblem(const Model& model, Formulation formulation, DerivativeMode mode,
                       QuadraticCost cost, int N, const TorqueLimits& limits)
    : model_(model),
      formulation_(formulation),
      mode_(mode),
      cost_(std::move(cost)),
      bounds_(limits, cost_.weights().R, cost_.n()),
      N_(N),
      lane_data_(model) {
  const int n = model.n;
  if (N < 1) throw std::invalid_argument("horizon steps N must be at least 1, got " + std::to_string(N));
  if (cost_.n() != n) {
    throw std::invalid_argument("the costs have " + std::to_string(cost_.n()) + " joints, the model " +
                                std::to_string(n));
  }
  if (formulation_ == Formulation::kForwardDynamics && (cost_.weights().R.array() <= 0).any()) {
    throw std::invalid_argument("the forward-dynamics problem needs R > 0 on every joint");
  }
  stage_.assign(static_cast<size_t>(N), Data(model));
  for (Vec* x : {&w_, &gq_, &gv_, &lq_, &lv_, &la_, &d_hat_, &tau_in_, &u_ref_}) *x = Vec::Zero(n);
  for (VecX<StagePack>* x : {&ql_, &vl_, &al_, &wl_, &ul_}) *x = VecX<StagePack>::Zero(n);
  rl_ = VecX<StagePack>::Zero(bounds_.m());
  // u_ref = ID(q_ref, 0, 0) − d̂: the torque that holds the target (DESIGN §8, §10)
  const Vec zero = Vec::Zero(n);
  tau_ref_ = rnea(model_, stage_[0], cost_.q_ref(), zero, zero);
  cost_.set_torque_reference(tau_ref_);
  for (MatX<double>* x : {&gq_all_, &gv_all_, &Mw_all_}) *x = MatX<double>::Zero(n, N);
  set_stages_in_lanes(true);
}

void OcpProblem::set_disturbance(const Vec& d_hat) {
  if (d_hat.size() != model_.n || !d_hat.allFinite()) {
    throw std::invalid_argument("disturbance estimate: expected " + std::to_string(model_.n) +
                                " finite values, got " + std::to_string(d_hat.size()));
  }
  d_hat_ = d_hat;
  u_ref_ = tau_ref_ - d_hat_;
  cost_.set_torque_reference(u_ref_);
}

void OcpProblem::set_target(const Vec& q_ref) {
  cost_.set_q_ref(q_ref);
  tau_ref_ = rnea(model_, stage_[0], cost_.q_ref(), w_.setZero(), la_.setZero());
  u_ref_ = tau_ref_ - d_hat_;
  cost_.set_torque_reference(u_ref_);
}

void OcpProblem::stage_dynamics(int i, In q, In v, In input, Out output) {
  assert(i >= 0 && i < N_);
  Data& d = stage_[static_cast<size_t>(i)];
  if (formulation_ == Formulation::kForwardDynamics) {
    tau_in_ = input + d_hat_;
    output = aba(model_, d, q, v, tau_in_);
  } else if (mode_ == DerivativeMode::kAdjoint) {
    output = rnea(model_, d, q, v, input) - d_hat_;
  } else {
    // the derivatives' forward pass gives τ too: no separate RNEA
    rnea_derivatives(model_, d, q, v, input);
    output = d.tau - d_hat_;
  }
}

namespace {

// lane k ← column i0 + min(k, count − 1) + shift of x: unused lanes repeat the last stage
void pack_lanes(const MatX<double>& x, int i0, int count, int shift, VecX<StagePack>& out) {
  for (int k = 0; k < kStageLanes; ++k) {
    const int i = i0 + std::min(k, count - 1) + shift;
    for (Eigen::Index j = 0; j < x.rows(); ++j) out[j][k] = x(j, i);
  }
}

// the model's torques τ = u + d̂ of the columns of the actuators' torques u, in lanes
void pack_torque_lanes(const MatX<double>& u, const VecX<double>& d_hat, int i0, int count, VecX<StagePack>& out) {
  pack_lanes(u, i0, count, 0, out);
  for (Eigen::Index j = 0; j < u.rows(); ++j) out[j] += d_hat[j];
}

// column i0 + k of out ← lane k, for the count stages in use
void unpack_lanes(const VecX<StagePack>& x, int i0, int count, MatX<double>& out) {
  for (int k = 0; k < count; ++k) {
    for (Eigen::Index j = 0; j < x.size(); ++j) out(j, i0 + k) = x[j][k];
  }
}

}  // namespace

// a = FD(q, v, u), μ = M⁻¹γ_{i+1}, (∂ID/∂q)ᵀμ and (∂ID/∂v)ᵀμ for up to kStageLanes stages per
// ABA; unused lanes repeat the last stage
void OcpProblem::stage_lanes_at_costates(int i0, int count, const MatX<double>& q, const MatX<double>& v,
                                         const MatX<double>& u, const MatX<double>& gmm, MatX<double>& a) {
  assert(costate_lanes_ && count >= 1 && count <= kStageLanes && i0 + count <= N_);
  pack_lanes(q, i0, count, 0, ql_);
  pack_lanes(v, i0, count, 0, vl_);
  pack_torque_lanes(u, d_hat_, i0, count, al_);  // the torque, in the acceleration's buffer
  pack_lanes(gmm, i0, count, 1, wl_);            // γ_{i+1}
  unpack_lanes(aba(model_, lane_data_, ql_, vl_, al_), i0, count, a);
  // μ = M⁻¹γ by the ABA factorization, then the RNEA part of the stage and its adjoint at μ
  const VecX<StagePack>& mu = minv_apply(model_, lane_data_, wl_);
  unpack_lanes(mu, i0, count, Mw_all_);
  al_ = mu;  // rnea_vjp reads its weights while it overwrites data: a copy
  rnea_after_aba(model_, lane_data_, ql_, vl_);
  rnea_vjp(model_, lane_data_, al_);
  unpack_lanes(lane_data_.g_q, i0, count, gq_all_);
  unpack_lanes(lane_data_.g_v, i0, count, gv_all_);
  costate_products_ = true;
}

// ∂q̈/∂q, ∂q̈/∂v and M⁻¹ for up to kStageLanes stages per ABA and its derivatives; unused lanes
// repeat the last stage
void OcpProblem::stage_derivative_lanes(int i0, int count, const MatX<double>& q, const MatX<double>& v,
                                        const MatX<double>& u) {
  assert(derivative_lanes_ && count >= 1 && count <= kStageLanes && i0 + count <= N_);
  const int n = model_.n;
  pack_lanes(q, i0, count, 0, ql_);
  pack_lanes(v, i0, count, 0, vl_);
  pack_torque_lanes(u, d_hat_, i0, count, al_);  // the torque, in the acceleration's buffer
  aba(model_, lane_data_, ql_, vl_, al_);
  aba_derivatives_after_aba(model_, lane_data_, ql_, vl_);
  for (int k = 0; k < count; ++k) {
    Data& d = stage_[static_cast<size_t>(i0 + k)];
    for (int c = 0; c < n; ++c) {
      for (int r = 0; r < n; ++r) {
        d.da_dq(r, c) = lane_data_.da_dq(r, c)[k];
        d.da_dv(r, c) = lane_data_.da_dv(r, c)[k];
        d.Minv(r, c) = lane_data_.Minv(r, c)[k];
      }
    }
  }
  derivatives_from_lanes_ = true;
}

// u = ID(q, v, a) and (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M w with w = ∂(L + ρᵀ(s∘c))/∂u, for up to kStageLanes stages
// per RNEA (with adjoints) or RNEA derivatives (matrix mode); unused lanes repeat the last stage
void OcpProblem::stage_dynamics_lanes(int i0, int count, const MatX<double>& q,
                                      const MatX<double>& v, const MatX<double>& a,
                                      const MatX<double>& rho, MatX<double>& u) {
  assert(lanes_ && count >= 1 && count <= kStageLanes && i0 + count <= N_);
  const int n = model_.n, m = bounds_.m();
  pack_lanes(q, i0, count, 0, ql_);
  pack_lanes(v, i0, count, 0, vl_);
  pack_lanes(a, i0, count, 0, al_);
  pack_lanes(rho, i0, count, 0, rl_);
  const bool adjoint = mode_ == DerivativeMode::kAdjoint;
  if (adjoint) {
    rnea(model_, lane_data_, ql_, vl_, al_);
  } else {
    rnea_derivatives(model_, lane_data_, ql_, vl_, al_);
  }
  // the actuators' torques u = τ − d̂; w = R(u − u_ref) + 2s∘ρ∘(u − ū) on the bounded joints
  for (int j = 0; j < n; ++j) ul_[j] = lane_data_.tau[j] - d_hat_[j];
  const VecX<double>& R = cost_.weights().R;
  const VecX<double>& u_ref = cost_.u_ref();
  for (int j = 0; j < n; ++j) wl_[j] = R[j] * (ul_[j] - u_ref[j]);
  for (int k = 0; k < m; ++k) {
    const int j = bounds_.joints()[static_cast<size_t>(k)];
    wl_[j] += (2.0 * bounds_.scale()[k]) * rl_[k] * (ul_[j] - bounds_.middle()[k]);
  }
  if (adjoint) {
    rnea_vjp(model_, lane_data_, wl_);
  } else {
    // (∂τ/∂q)ᵀw, (∂τ/∂v)ᵀw and M w (M symmetric) column by column: Eigen's products cannot take
    // SIMD packs
    for (int c = 0; c < n; ++c) {
      StagePack gq(0.0), gv(0.0), ga(0.0);
      for (int r = 0; r < n; ++r) {
        gq += lane_data_.dtau_dq(r, c) * wl_[r];
        gv += lane_data_.dtau_dv(r, c) * wl_[r];
        ga += lane_data_.M(r, c) * wl_[r];
      }
      lane_data_.g_q[c] = gq;
      lane_data_.g_v[c] = gv;
      lane_data_.g_a[c] = ga;
    }
  }
  unpack_lanes(ul_, i0, count, u);
  unpack_lanes(lane_data_.g_q, i0, count, gq_all_);
  unpack_lanes(lane_data_.g_v, i0, count, gv_all_);
  unpack_lanes(lane_data_.g_a, i0, count, Mw_all_);
}

void OcpProblem::stage_hamiltonian(int i, In q, In v, In a, In u, In d, In rho, In lmd_next,
                                   In gmm_next, Out hq, Out hv, Out F, bool state) {
  assert(i >= 0 && i < N_);
  Data& data = stage_[static_cast<size_t>(i)];
  const int n = model_.n, m = bounds_.m();
  auto hu = F.head(n);
  // w = ∂(L + ρᵀ(s∘c))/∂u = R(u − u_ref) + 2s∘ρ∘(u − ū) (on the bounded joints)
  auto torque_gradient = [&] {
    cost_.torque_gradient(u, w_);
    bounds_.add_torque_gradient(u, rho, w_);
  };
  // gq_, gv_: the dynamics' part of ∂H/∂q, ∂H/∂v
  if (formulation_ == Formulation::kInverseDynamics) {
    // gq = (∂ID/∂q)ᵀw,  gv = (∂ID/∂v)ᵀw;  hu = γ_{i+1} + ∂L/∂a + M w
    cost_.acceleration_gradient(a, la_);
    if (lanes_) {
      gq_ = gq_all_.col(i);
      gv_ = gv_all_.col(i);
      hu = gmm_next + la_ + Mw_all_.col(i);
    } else if (mode_ == DerivativeMode::kAdjoint) {
      torque_gradient();
      rnea_vjp(model_, data, w_);  // rnea at (q, v, a) is in data from stage_dynamics
      gq_ = data.g_q;
      gv_ = data.g_v;
      hu = gmm_next + la_ + data.g_a;
    } else {
      // ∂τ/∂q, ∂τ/∂v and M are in data from stage_dynamics
      torque_gradient();
      hu = gmm_next + la_;
      hu.noalias() += data.M * w_;
      if (state) {
        gq_.noalias() = data.dtau_dq.transpose() * w_;
        gv_.noalias() = data.dtau_dv.transpose() * w_;
      }
    }
  } else {
    // μ = M⁻¹γ_{i+1};  gq = −(∂ID/∂q)ᵀμ = (∂FD/∂q)ᵀγ,  gv likewise;  hu = w + μ
    torque_gradient();
    if (costate_products_) {
      // from stage_lanes_at_costates, at these costates
      hu = w_ + Mw_all_.col(i);
      gq_ = -gq_all_.col(i);
      gv_ = -gv_all_.col(i);
    } else if (mode_ == DerivativeMode::kAdjoint || !state) {
      const VecX<double>& mu = minv_apply(model_, data, gmm_next);  // ABA factorization of stage i
      hu = w_ + mu;
      if (state) {
        rnea_after_aba(model_, data, q, v);  // a = data.qdd: the stage's aba pass, completed
        rnea_vjp(model_, data, mu);
        gq_ = -data.g_q;
        gv_ = -data.g_v;
      }
    } else {
      // from stage_derivative_lanes, or now: ABA of stage i is in data from stage_dynamics
      if (!derivatives_from_lanes_) aba_derivatives_after_aba(model_, data, q, v);
      gq_.noalias() = data.da_dq.transpose() * gmm_next;
      gv_.noalias() = data.da_dv.transpose() * gmm_next;
      hu = w_;
      hu.noalias() += data.Minv.transpose() * gmm_next;
    }
  }
  // ∂H/∂d = −r_d + 2s∘ρ∘d,  ∂H/∂ρ = s∘c
  if (m > 0) bounds_.dummy_gradients(u, d, rho, F.segment(n, m), F.segment(n + m, m));
  if (!state) return;
  // hq = ∂L/∂q + gq;  hv = ∂L/∂v + λ_{i+1} + gv (the Euler step q_{i+1} = q_i + Δτ v_i)
  cost_.state_gradient(q, v, lq_, lv_);
  hq = lq_ + gq_;
  hv = lv_ + lmd_next + gv_;
}

}  // namespace idmpc
