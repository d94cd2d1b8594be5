#include "idmpc/ocp/ocp.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>

#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {

std::string to_string(Formulation f) {
  return f == Formulation::kForwardDynamics ? "fd" : "id";
}
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

namespace {

void check_size(const VecX<double>& x, int n, const char* what) {
  if (x.size() != n) {
    throw std::invalid_argument(std::string(what) + " has " + std::to_string(x.size()) +
                                " entries, expected " + std::to_string(n) + " (one per joint)");
  }
  if (!x.allFinite() ) throw std::invalid_argument(std::string(what) + " is not finite");
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

Ocp::Ocp(const Model& model, Formulation formulation, DerivativeMode mode, OcpWeights weights,
         VecX<double> q_ref, int N)
    : model_(model),
      formulation_(formulation),
      mode_(mode),
      weights_(std::move(weights)),
      q_ref_(std::move(q_ref)),
      N_(N),
      pack_data_(model),
      control_data_(model) {
  const int n = model.n;
  if (N < 1) throw std::invalid_argument("horizon steps N must be at least 1, got " + std::to_string(N));
  check_size(weights_.Qq, n, "weight Qq");
  check_size(weights_.Qv, n, "weight Qv");
  check_size(weights_.Qa, n, "weight Qa");
  check_size(weights_.R, n, "weight R");
  check_size(q_ref_, n, "q_ref");
  if (formulation_ == Formulation::kForwardDynamics && (weights_.R.array() <= 0).any()) {
    throw std::invalid_argument("the forward-dynamics problem needs R > 0 on every joint");
  }
  stage_.assign(static_cast<size_t>(N), Data(model));
  q_ = MatX<double>::Zero(n, N + 1);
  v_ = MatX<double>::Zero(n, N + 1);
  a_ = MatX<double>::Zero(n, N);
  u_ = MatX<double>::Zero(n, N);
  for (VecX<double>* x : {&lmd_, &gmm_, &lmd_next_, &gmm_next_, &gq_, &gv_, &w_, &qt_, &vt_}) {
    *x = VecX<double>::Zero(n);
  }
  for (VecX<StagePack>* x : {&qp_, &vp_, &ap_, &wp_}) *x = VecX<StagePack>::Zero(n);
  for (MatX<double>* x : {&gq_all_, &gv_all_, &Mw_all_}) *x = MatX<double>::Zero(n, N);
  batched_ = batchable();
}

// ID with adjoints: u_i = ID(q_i, v_i, a_i) and (∂ID/∂q)ᵀw_i, (∂ID/∂v)ᵀw_i, M w_i with
// w_i = R u_i for kStageLanes stages per RNEA; the last group repeats its last stage
void Ocp::batched_stage_dynamics(int stages) {
  const int n = model_.n;
  for (int i0 = 0; i0 < stages; i0 += kStageLanes) {
    for (int k = 0; k < kStageLanes; ++k) {
      const int i = std::min(i0 + k, stages - 1);
      for (int j = 0; j < n; ++j) {
        qp_[j][k] = q_(j, i);
        vp_[j][k] = v_(j, i);
        ap_[j][k] = a_(j, i);
      }
    }
    const VecX<StagePack>& tau = rnea(model_, pack_data_, qp_, vp_, ap_);
    for (int j = 0; j < n; ++j) wp_[j] = weights_.R[j] * tau[j];
    rnea_vjp(model_, pack_data_, wp_);
    for (int k = 0; k < kStageLanes && i0 + k < stages; ++k) {
      const int i = i0 + k;
      for (int j = 0; j < n; ++j) {
        u_(j, i) = tau[j][k];
        gq_all_(j, i) = pack_data_.g_q[j][k];
        gv_all_(j, i) = pack_data_.g_v[j][k];
        Mw_all_(j, i) = pack_data_.g_a[j][k];
      }
    }
  }
}

// forward dynamics: a_i = FD(q_i, v_i, u_i); inverse dynamics: u_i = ID(q_i, v_i, a_i), with
// the RNEA derivatives at once in matrix mode (the rollout does not depend on u)
void Ocp::stage_forward(int i) {
  Data& d = stage_[i];
  if (formulation_ == Formulation::kForwardDynamics) {
    a_.col(i) = aba(model_, d, q_.col(i), v_.col(i), u_.col(i));
  } else if (mode_ == DerivativeMode::kAdjoint) {
    u_.col(i) = rnea(model_, d, q_.col(i), v_.col(i), a_.col(i));
  } else {
    // the derivatives' forward pass gives τ too: no separate RNEA
    rnea_derivatives(model_, d, q_.col(i), v_.col(i), a_.col(i));
    u_.col(i) = d.tau;
  }
}

// gq_, gv_ = the dynamics' contribution to the costate equations; F_i = stage residual
void Ocp::stage_backward(int i, const VecX<double>& gmm_next, Eigen::Ref<VecX<double>> F_i) {
  Data& d = stage_[i];
  const auto q = q_.col(i), v = v_.col(i), a = a_.col(i), u = u_.col(i);
  if (batched_) {
    gq_ = gq_all_.col(i);
    gv_ = gv_all_.col(i);
    F_i = gmm_next + weights_.Qa.cwiseProduct(a) + Mw_all_.col(i);
    return;
  }
  if (formulation_ == Formulation::kInverseDynamics) {
    // w = R u;  gq = (∂ID/∂q)ᵀw,  gv = (∂ID/∂v)ᵀw;  F_i = γ_{i+1} + Q_a a + M w
    w_ = weights_.R.cwiseProduct(u);
    if (mode_ == DerivativeMode::kAdjoint) {
      rnea_vjp(model_, d, w_);  // rnea at (q, v, a) is in d from the forward sweep
      gq_ = d.g_q;
      gv_ = d.g_v;
      F_i = gmm_next + weights_.Qa.cwiseProduct(a) + d.g_a;
    } else {
      // ∂τ/∂q, ∂τ/∂v and M are in d from the forward sweep
      gq_.noalias() = d.dtau_dq.transpose() * w_;
      gv_.noalias() = d.dtau_dv.transpose() * w_;
      F_i = gmm_next + weights_.Qa.cwiseProduct(a);
      F_i.noalias() += d.M * w_;
    }
  } else {
    // μ = M⁻¹γ_{i+1};  gq = −(∂ID/∂q)ᵀμ = (∂FD/∂q)ᵀγ,  gv likewise;  F_i = R u + μ
    if (mode_ == DerivativeMode::kAdjoint) {
      const VecX<double>& mu = minv_apply(model_, d, gmm_next);  // ABA factorization of stage i
      rnea(model_, d, q, v, a);
      rnea_vjp(model_, d, mu);
      gq_ = -d.g_q;
      gv_ = -d.g_v;
      F_i = weights_.R.cwiseProduct(u) + mu;
    } else {
      aba_derivatives_after_aba(model_, d, q, v);  // ABA of stage i is in d from the forward sweep
      gq_.noalias() = d.da_dq.transpose() * gmm_next;
      gv_.noalias() = d.da_dv.transpose() * gmm_next;
      F_i = weights_.R.cwiseProduct(u);
      F_i.noalias() += d.Minv.transpose() * gmm_next;
    }
  }
}

void Ocp::residual(const Eigen::Ref<const VecX<double>>& U, const Eigen::Ref<const VecX<double>>& q0,
                   const Eigen::Ref<const VecX<double>>& v0, double T, Eigen::Ref<VecX<double>> F,
                   int stages) {
  const int n = model_.n;
  assert(stages >= 1 && stages <= N_ && U.size() >= stages * n && F.size() >= stages * n);
  const double dtau = T / stages;
  const auto t0 = timing_ ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};

  // forward sweep: explicit Euler from the measured state (eq. 12)
  q_.col(0) = q0;
  v_.col(0) = v0;
  auto& input = formulation_ == Formulation::kForwardDynamics ? u_ : a_;
  for (int i = 0; i < stages; ++i) {
    input.col(i) = U.segment(i * n, n);
    if (!batched_) stage_forward(i);
    q_.col(i + 1) = q_.col(i) + dtau * v_.col(i);
    v_.col(i + 1) = v_.col(i) + dtau * a_.col(i);
  }
  if (batched_) batched_stage_dynamics(stages);
  const auto t1 = timing_ ? std::chrono::steady_clock::now() : t0;

  // terminal costates (eqs. 16, 18), then the backward sweep (eqs. 22–24)
  lmd_next_ = weights_.Qq.cwiseProduct(q_.col(stages) - q_ref_);
  gmm_next_ = weights_.Qv.cwiseProduct(v_.col(stages));
  for (int i = stages - 1; i >= 0; --i) {
    stage_backward(i, gmm_next_, F.segment(i * n, n));
    lmd_ = lmd_next_ + dtau * (weights_.Qq.cwiseProduct(q_.col(i) - q_ref_) + gq_);
    gmm_ = gmm_next_ + dtau * (weights_.Qv.cwiseProduct(v_.col(i)) + lmd_next_ + gv_);
    lmd_next_.swap(lmd_);
    gmm_next_.swap(gmm_);
  }
  if (timing_) {
    times_.rollout += std::chrono::duration<double>(t1 - t0).count();
    times_.costate += seconds_since(t1);
  }
  ++times_.evaluations;
}

void Ocp::applied_torque(const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                         const Eigen::Ref<const VecX<double>>& U,
                         const Eigen::Ref<const VecX<double>>& a0_previous, double dt,
                         Eigen::Ref<VecX<double>> tau) {
  const int n = model_.n;
  if (formulation_ == Formulation::kForwardDynamics) {
    tau = U.head(n);
    return;
  }
  // delay-compensated inverse dynamics (paper eqs. 27–28)
  qt_ = q + dt * v;
  vt_ = v + dt * a0_previous;
  tau = rnea(model_, control_data_, qt_, vt_, U.head(n));
}

}  // namespace idmpc
