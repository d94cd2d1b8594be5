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
      lanes_(model, Lanes ? kernel_parts<M>() | DataParts::rnea_vjp() : DataParts()),
      scratch_(model.n),
      dual_stamp_(N),
      N_(N) {
  const int n = model.n, nl = Lanes ? n : 0;
  for (VecX<StagePack>* x : {&ql_, &vl_, &al_, &wl_, &ul_}) *x = VecX<StagePack>::Zero(nl);
  rl_ = VecX<StagePack>::Zero(Lanes ? m : 0);
  for (MatX<double>* x : {&gq_all_, &gv_all_, &Mw_all_}) *x = MatX<double>::Zero(nl, Lanes ? N : 0);
}

template <DerivativeMode M, bool Lanes> void IdStages<M, Lanes>::reserve_dual(const Model& model) {
  if (dual_reserved_) return;
  dual_stage_.assign(static_cast<size_t>(N_), DataTpl<Dual>(model, kernel_parts<M>()));
  dual_scratch_ = Scratch<Dual>(model.n);
  dual_reserved_ = true;
}

template <DerivativeMode M, bool Lanes>
template <typename S>
void IdStages<M, Lanes>::stage_dynamics(const StageTerms& terms, DataTpl<S>& data, const Eigen::Ref<const VecX<S>>& q,
                                        const Eigen::Ref<const VecX<S>>& v, const Eigen::Ref<const VecX<S>>& a,
                                        Eigen::Ref<VecX<S>> u) {
  if constexpr (kMatrix) {
    // the derivatives' forward pass gives τ too: no separate RNEA
    rnea_derivatives(terms.model(), data, q, v, a);
    u = data.tau - terms.disturbance();
  } else {
    u = rnea(terms.model(), data, q, v, a) - terms.disturbance();
  }
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) {
  if constexpr (Lanes) {
    // one stage by itself: its products are not kept, so the Hamiltonian needs at_states
    (void)ev;
    output = rnea(terms.model(), single_, q, v, input) - terms.disturbance();
  } else {
    assert(i >= 0 && i < static_cast<int>(stage_.size()));
    stage_dynamics<double>(terms, stage_[static_cast<size_t>(i)], q, v, input, output);
    stamp_.stamp(i, ev);
  }
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::dynamics(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn input,
                                  DualOut output) {
  require_dual();
  assert(i >= 0 && i < static_cast<int>(dual_stage_.size()));
  stage_dynamics<Dual>(terms, dual_stage_[static_cast<size_t>(i)], q, v, input, output);
  dual_stamp_.stamp(i, ev);
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

// gq = (∂ID/∂q)ᵀw,  gv = (∂ID/∂v)ᵀw;  hu = γ_{i+1} + ∂L/∂a + M w
template <DerivativeMode M, bool Lanes>
template <typename S>
void IdStages<M, Lanes>::stage_hamiltonian(const StageTerms& terms, int i, DataTpl<S>& data, Scratch<S>& s,
                                           const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                                           const Eigen::Ref<const VecX<S>>& a, const Eigen::Ref<const VecX<S>>& u,
                                           const Eigen::Ref<const VecX<S>>& d, const Eigen::Ref<const VecX<S>>& rho,
                                           const Eigen::Ref<const VecX<S>>& lmd_next,
                                           const Eigen::Ref<const VecX<S>>& gmm_next, Eigen::Ref<VecX<S>> hq,
                                           Eigen::Ref<VecX<S>> hv, Eigen::Ref<VecX<S>> F, bool state) {
  auto hu = F.head(terms.n());
  terms.cost().acceleration_gradient(a, s.la);
  terms.torque_gradient(i, u, rho, s.w);
  if constexpr (kMatrix) {
    // ∂τ/∂q, ∂τ/∂v and M are in data from the dynamics
    hu = gmm_next + s.la;
    hu.noalias() += data.M * s.w;
    if (state) {
      s.gq.noalias() = data.dtau_dq.transpose() * s.w;
      s.gv.noalias() = data.dtau_dv.transpose() * s.w;
    }
  } else {
    rnea_vjp(terms.model(), data, s.w);  // rnea at (q, v, a) is in data from the dynamics
    s.gq = data.g_q;
    s.gv = data.g_v;
    hu = gmm_next + s.la + data.g_a;
  }
  terms.close_stage(i, q, v, u, d, rho, lmd_next, s.gq, s.gv, hq, hv, F, state, s.frame);
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In a, In u, In d,
                                     In rho, In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) {
  stamp_.require(i, ev, "the Hamiltonian");
  if constexpr (Lanes) {
    // the products from the lanes
    Scratch<double>& s = scratch_;
    terms.cost().acceleration_gradient(a, s.la);
    s.gq = gq_all_.col(i);
    s.gv = gv_all_.col(i);
    F.head(terms.n()) = gmm_next + s.la + Mw_all_.col(i);
    terms.close_stage(i, q, v, u, d, rho, lmd_next, s.gq, s.gv, hq, hv, F, state, s.frame);
  } else {
    stage_hamiltonian<double>(terms, i, stage_[static_cast<size_t>(i)], scratch_, q, v, a, u, d, rho, lmd_next,
                              gmm_next, hq, hv, F, state);
  }
}

template <DerivativeMode M, bool Lanes>
void IdStages<M, Lanes>::hamiltonian(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn a,
                                     DualIn u, DualIn d, DualIn rho, DualIn lmd_next, DualIn gmm_next, DualOut hq,
                                     DualOut hv, DualOut F, bool state) {
  require_dual();
  dual_stamp_.require(i, ev, "the Hamiltonian");
  stage_hamiltonian<Dual>(terms, i, dual_stage_[static_cast<size_t>(i)], dual_scratch_, q, v, a, u, d, rho,
                          lmd_next, gmm_next, hq, hv, F, state);
}

template <DerivativeMode M, bool Lanes> std::size_t IdStages<M, Lanes>::workspace_bytes() const {
  std::size_t b = stage_.capacity() * sizeof(Data) + heap_bytes(single_) + heap_bytes(lanes_);
  for (const Data& d : stage_) b += heap_bytes(d);
  b += dual_stage_.capacity() * sizeof(DataTpl<Dual>);
  for (const DataTpl<Dual>& d : dual_stage_) b += heap_bytes(d);
  for (const MatX<double>* x : {&gq_all_, &gv_all_, &Mw_all_}) b += static_cast<std::size_t>(x->size()) * sizeof(double);
  return b;
}

template class IdStages<DerivativeMode::kMatrix, false>;
template class IdStages<DerivativeMode::kMatrix, true>;
template class IdStages<DerivativeMode::kAdjoint, false>;
template class IdStages<DerivativeMode::kAdjoint, true>;

}  // namespace idmpc
