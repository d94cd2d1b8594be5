#include "idmpc/ocp/id_stages.hpp"

#include <cassert>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/ocp/stage_lanes.hpp"

namespace idmpc {
namespace {

template <DerivativeMode M> DataParts kernel_parts() {
  if constexpr (M == DerivativeMode::kAdjoint) return DataParts::rnea() | DataParts::rnea_vjp();
  return DataParts::rnea() | DataParts::rnea_derivatives();
}

}  // namespace

template <DerivativeMode M, bool Lanes>
IdStages<M, Lanes>::IdStages(const Model& model, int N, int m)
    : stage_(Lanes ? 0 : static_cast<size_t>(N), Data(model, Lanes ? DataParts() : kernel_parts<M>())),
      single_(model, Lanes ? DataParts::rnea() : DataParts()),
      stamp_(N),
      // in matrix mode the lanes' products go to g_q, g_v, g_a too
      lanes_(model, Lanes ? kernel_parts<M>() | DataParts::rnea_vjp() : DataParts()) {
  const int n = model.n, nl = Lanes ? n : 0;
  for (VecX<StagePack>* x : {&ql_, &vl_, &al_, &wl_, &ul_}) *x = VecX<StagePack>::Zero(nl);
  rl_ = VecX<StagePack>::Zero(Lanes ? m : 0);
  for (MatX<double>* x : {&gq_all_, &gv_all_, &Mw_all_}) *x = MatX<double>::Zero(nl, Lanes ? N : 0);
  for (Vec* x : {&w_, &gq_, &gv_, &la_}) *x = Vec::Zero(n);
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) {
  if constexpr (Lanes) {
    // one stage by itself: its products are not kept, so the Hamiltonian needs at_states
    (void)ev;
    output = rnea(terms.model(), single_, q, v, input) - terms.disturbance();
  } else {
    assert(i >= 0 && i < static_cast<int>(stage_.size()));
    Data& data = stage_[static_cast<size_t>(i)];
    if constexpr (kMatrix) {
      // the derivatives' forward pass gives τ too: no separate RNEA
      rnea_derivatives(terms.model(), data, q, v, input);
      output = data.tau - terms.disturbance();
    } else {
      output = rnea(terms.model(), data, q, v, input) - terms.disturbance();
    }
    stamp_.stamp(i, ev);
  }
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::at_states(const StageTerms& terms, Evaluation ev, StageTrajectories& x) {
  // the rollout does not depend on u: the stages' dynamics afterwards
  if constexpr (Lanes) {
    for (int i0 = 0; i0 < x.stages; i0 += kStageLanes) lanes(terms, ev, i0, std::min(kStageLanes, x.stages - i0), x);
  } else {
    for (int i = 0; i < x.stages; ++i) dynamics(terms, ev, i, x.q.col(i), x.v.col(i), x.a.col(i), x.u.col(i));
  }
}

// u = ID(q, v, a) − d̂ and (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M w for up to kStageLanes stages per RNEA
// (with adjoints) or RNEA derivatives (matrix mode); unused lanes repeat the last stage
template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::lanes(const StageTerms& terms, Evaluation ev, int i0, int count, StageTrajectories& x) {
  const Model& model = terms.model();
  const int n = model.n;
  detail::pack_lanes(x.q, i0, count, 0, ql_);
  detail::pack_lanes(x.v, i0, count, 0, vl_);
  detail::pack_lanes(x.a, i0, count, 0, al_);
  detail::pack_lanes(x.rho, i0, count, 0, rl_);
  if constexpr (kMatrix) {
    rnea_derivatives(model, lanes_, ql_, vl_, al_);
  } else {
    rnea(model, lanes_, ql_, vl_, al_);
  }
  // the actuators' torques u = τ − d̂
  const VecX<double>& d_hat = terms.disturbance();
  for (int j = 0; j < n; ++j) ul_[j] = lanes_.tau[j] - d_hat[j];
  terms.torque_gradient(i0, count, ul_, rl_, wl_);
  if constexpr (kMatrix) {
    // (∂τ/∂q)ᵀw, (∂τ/∂v)ᵀw and M w (M symmetric) column by column: Eigen's products cannot take
    // SIMD packs
    for (int c = 0; c < n; ++c) {
      StagePack gq(0.0), gv(0.0), ga(0.0);
      for (int r = 0; r < n; ++r) {
        gq += lanes_.dtau_dq(r, c) * wl_[r];
        gv += lanes_.dtau_dv(r, c) * wl_[r];
        ga += lanes_.M(r, c) * wl_[r];
      }
      lanes_.g_q[c] = gq;
      lanes_.g_v[c] = gv;
      lanes_.g_a[c] = ga;
    }
  } else {
    rnea_vjp(model, lanes_, wl_);
  }
  detail::unpack_lanes(ul_, i0, count, x.u);
  detail::unpack_lanes(lanes_.g_q, i0, count, gq_all_);
  detail::unpack_lanes(lanes_.g_v, i0, count, gv_all_);
  detail::unpack_lanes(lanes_.g_a, i0, count, Mw_all_);
  for (int k = 0; k < count; ++k) stamp_.stamp(i0 + k, ev);
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In a, In u, In d,
                                     In rho, In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) {
  stamp_.require(i, ev, "the Hamiltonian");
  auto hu = F.head(terms.n());
  // gq = (∂ID/∂q)ᵀw,  gv = (∂ID/∂v)ᵀw;  hu = γ_{i+1} + ∂L/∂a + M w
  terms.cost().acceleration_gradient(a, la_);
  if constexpr (Lanes) {
    gq_ = gq_all_.col(i);
    gv_ = gv_all_.col(i);
    hu = gmm_next + la_ + Mw_all_.col(i);
  } else {
    Data& data = stage_[static_cast<size_t>(i)];
    terms.torque_gradient(i, u, rho, w_);
    if constexpr (kMatrix) {
      // ∂τ/∂q, ∂τ/∂v and M are in data from dynamics
      hu = gmm_next + la_;
      hu.noalias() += data.M * w_;
      if (state) {
        gq_.noalias() = data.dtau_dq.transpose() * w_;
        gv_.noalias() = data.dtau_dv.transpose() * w_;
      }
    } else {
      rnea_vjp(terms.model(), data, w_);  // rnea at (q, v, a) is in data from dynamics
      gq_ = data.g_q;
      gv_ = data.g_v;
      hu = gmm_next + la_ + data.g_a;
    }
  }
  terms.close_stage(i, q, v, u, d, rho, lmd_next, gq_, gv_, hq, hv, F, state);
}

template <DerivativeMode M, bool Lanes> std::size_t IdStages<M, Lanes>::workspace_bytes() const {
  std::size_t b = stage_.capacity() * sizeof(Data) + heap_bytes(single_) + heap_bytes(lanes_);
  for (const Data& d : stage_) b += heap_bytes(d);
  for (const MatX<double>* x : {&gq_all_, &gv_all_, &Mw_all_}) b += static_cast<std::size_t>(x->size()) * sizeof(double);
  return b;
}

template class IdStages<DerivativeMode::kMatrix, false>;
template class IdStages<DerivativeMode::kMatrix, true>;
template class IdStages<DerivativeMode::kAdjoint, false>;
template class IdStages<DerivativeMode::kAdjoint, true>;

}  // namespace idmpc
