#include "idmpc/ocp/fd_stages.hpp"

#include <cassert>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/ocp/stage_lanes.hpp"

namespace idmpc {
namespace {

template <DerivativeMode M, bool Lanes> DataParts stage_parts() {
  const DataParts aba = DataParts::rnea() | DataParts::aba() | DataParts::minv_apply();
  if constexpr (M == DerivativeMode::kAdjoint) return aba | DataParts::rnea_vjp();
  if constexpr (Lanes) return aba;
  return aba | DataParts::rnea_derivatives() | DataParts::minv_matrix() | DataParts::aba_derivatives();
}

template <DerivativeMode M, bool Lanes> DataParts lane_parts() {
  if constexpr (!Lanes) return DataParts();
  const DataParts aba = DataParts::rnea() | DataParts::aba();
  if constexpr (M == DerivativeMode::kAdjoint) return aba | DataParts::minv_apply() | DataParts::rnea_vjp();
  return aba | DataParts::rnea_derivatives() | DataParts::minv_matrix() | DataParts::aba_derivatives();
}

}  // namespace

template <DerivativeMode M, bool Lanes>
FdStages<M, Lanes>::FdStages(const Model& model, int N)
    : stage_(static_cast<size_t>(N), Data(model, stage_parts<M, Lanes>())),
      dynamics_stamp_(N),
      lanes_stamp_(N),
      lanes_(model, lane_parts<M, Lanes>()),
      scratch_(model.n),
      dual_stamp_(N) {
  const int n = model.n, nl = Lanes ? n : 0;
  if constexpr (kDerivativeLanes) {
    derivatives_.assign(static_cast<size_t>(N),
                        Derivatives{MatX<double>::Zero(n, n), MatX<double>::Zero(n, n), MatX<double>::Zero(n, n)});
  }
  for (VecX<StagePack>* x : {&ql_, &vl_, &tl_, &gl_}) *x = VecX<StagePack>::Zero(nl);
  const int Nc = kCostateLanes ? N : 0;
  for (MatX<double>* x : {&mu_all_, &gq_all_, &gv_all_}) *x = MatX<double>::Zero(kCostateLanes ? n : 0, Nc);
}

template <DerivativeMode M, bool Lanes> void FdStages<M, Lanes>::reserve_dual(const Model& model) {
  if (dual_reserved_) return;
  dual_stage_.assign(stage_.size(), DataTpl<Dual>(model, stage_parts<M, false>()));
  dual_scratch_ = Scratch<Dual>(model.n);
  dual_reserved_ = true;
}

template <DerivativeMode M, bool Lanes>
template <typename S>
void FdStages<M, Lanes>::stage_dynamics(const StageTerms& terms, DataTpl<S>& data, Scratch<S>& s,
                                        const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                                        const Eigen::Ref<const VecX<S>>& u, Eigen::Ref<VecX<S>> a) {
  s.tau = u + terms.disturbance();
  a = aba(terms.model(), data, q, v, s.tau);
}

template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) {
  assert(i >= 0 && i < static_cast<int>(stage_.size()));
  stage_dynamics<double>(terms, stage_[static_cast<size_t>(i)], scratch_, q, v, input, output);
  dynamics_stamp_.stamp(i, ev);
}

template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::dynamics(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn input,
                                  DualOut output) {
  require_dual();
  assert(i >= 0 && i < static_cast<int>(dual_stage_.size()));
  stage_dynamics<Dual>(terms, dual_stage_[static_cast<size_t>(i)], dual_scratch_, q, v, input, output);
  dual_stamp_.stamp(i, ev);
}

template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::at_states(const StageTerms& terms, Evaluation ev, StageTrajectories& x) {
  if constexpr (kDerivativeLanes) {
    // stage 0 needs no state derivatives (its costates λ_0, γ_0 are never used)
    for (int i0 = 1; i0 < x.stages; i0 += kStageLanes) {
      derivative_lanes(terms, ev, i0, std::min(kStageLanes, x.stages - i0), x);
    }
  }
}

template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::at_costates(const StageTerms& terms, Evaluation ev, StageTrajectories& x) {
  assert(x.gmm != nullptr);
  if constexpr (kCostateLanes) {
    for (int i0 = 0; i0 < x.stages; i0 += kStageLanes) {
      costate_lanes(terms, ev, i0, std::min(kStageLanes, x.stages - i0), x);
    }
  } else {
    for (int i = 0; i < x.stages; ++i) dynamics(terms, ev, i, x.q.col(i), x.v.col(i), x.u.col(i), x.a.col(i));
    at_states(terms, ev, x);
  }
}

// ∂q̈/∂q, ∂q̈/∂v and M⁻¹ for up to kStageLanes stages per ABA and its derivatives; unused lanes
// repeat the last stage
template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::derivative_lanes(const StageTerms& terms, Evaluation ev, int i0, int count,
                                          const StageTrajectories& x) {
  const Model& model = terms.model();
  const int n = model.n;
  detail::pack_lanes(x.q, i0, count, 0, ql_);
  detail::pack_lanes(x.v, i0, count, 0, vl_);
  detail::pack_torque_lanes(x.u, terms.disturbance(), i0, count, tl_);
  aba(model, lanes_, ql_, vl_, tl_);
  aba_derivatives_after_aba(model, lanes_, ql_, vl_);
  for (int k = 0; k < count; ++k) {
    Derivatives& d = derivatives_[static_cast<size_t>(i0 + k)];
    for (int c = 0; c < n; ++c) {
      for (int r = 0; r < n; ++r) {
        d.da_dq(r, c) = lanes_.da_dq(r, c)[k];
        d.da_dv(r, c) = lanes_.da_dv(r, c)[k];
        d.Minv(r, c) = lanes_.Minv(r, c)[k];
      }
    }
    lanes_stamp_.stamp(i0 + k, ev);
  }
}

// a = FD(q, v, u), μ = M⁻¹γ_{i+1}, (∂ID/∂q)ᵀμ and (∂ID/∂v)ᵀμ for up to kStageLanes stages per
// ABA; unused lanes repeat the last stage
template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::costate_lanes(const StageTerms& terms, Evaluation ev, int i0, int count,
                                       StageTrajectories& x) {
  const Model& model = terms.model();
  detail::pack_lanes(x.q, i0, count, 0, ql_);
  detail::pack_lanes(x.v, i0, count, 0, vl_);
  detail::pack_torque_lanes(x.u, terms.disturbance(), i0, count, tl_);
  detail::pack_lanes(*x.gmm, i0, count, 1, gl_);  // γ_{i+1}
  detail::unpack_lanes(aba(model, lanes_, ql_, vl_, tl_), i0, count, x.a);
  // μ = M⁻¹γ by the ABA factorization, then the RNEA part of the stage and its adjoint at μ
  const VecX<StagePack>& mu = minv_apply(model, lanes_, gl_);
  detail::unpack_lanes(mu, i0, count, mu_all_);
  gl_ = mu;  // rnea_vjp reads its weights while it overwrites data: a copy
  rnea_after_aba(model, lanes_, ql_, vl_);
  rnea_vjp(model, lanes_, gl_);
  detail::unpack_lanes(lanes_.g_q, i0, count, gq_all_);
  detail::unpack_lanes(lanes_.g_v, i0, count, gv_all_);
  for (int k = 0; k < count; ++k) lanes_stamp_.stamp(i0 + k, ev);
}

// μ = M⁻¹γ_{i+1};  gq = −(∂ID/∂q)ᵀμ = (∂FD/∂q)ᵀγ,  gv likewise;  hu = w + μ
template <DerivativeMode M, bool Lanes>
template <typename S>
void FdStages<M, Lanes>::stage_hamiltonian(const StageTerms& terms, int i, DataTpl<S>& data, Scratch<S>& s,
                                           const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                                           const Eigen::Ref<const VecX<S>>& u, const Eigen::Ref<const VecX<S>>& d,
                                           const Eigen::Ref<const VecX<S>>& rho,
                                           const Eigen::Ref<const VecX<S>>& lmd_next,
                                           const Eigen::Ref<const VecX<S>>& gmm_next, Eigen::Ref<VecX<S>> hq,
                                           Eigen::Ref<VecX<S>> hv, Eigen::Ref<VecX<S>> F, bool state) {
  const Model& model = terms.model();
  auto hu = F.head(model.n);
  terms.torque_gradient(i, u, rho, s.w);
  if (!kMatrix || !state) {
    // μ by the stage's ABA factorization, then the RNEA part of the stage and its adjoint at μ
    // (matrix mode: stage 0, whose state derivatives are never used)
    const VecX<S>& mu = minv_apply(model, data, gmm_next);
    hu = s.w + mu;
    if (state) {
      if constexpr (!kMatrix) {
        rnea_after_aba(model, data, q, v);  // a = data.qdd: the stage's aba pass, completed
        rnea_vjp(model, data, mu);
        s.gq = -data.g_q;
        s.gv = -data.g_v;
      }
    }
  } else {
    // the derivative matrices from the stage's ABA in data
    aba_derivatives_after_aba(model, data, q, v);
    s.gq.noalias() = data.da_dq.transpose() * gmm_next;
    s.gv.noalias() = data.da_dv.transpose() * gmm_next;
    hu = s.w;
    hu.noalias() += data.Minv.transpose() * gmm_next;
  }
  terms.close_stage(i, q, v, u, d, rho, lmd_next, s.gq, s.gv, hq, hv, F, state, s.frame);
}

template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In, In u, In d,
                                     In rho, In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) {
  assert(i >= 0 && i < static_cast<int>(stage_.size()));
  if constexpr (kCostateLanes) {
    if (lanes_stamp_.current(i, ev)) {
      // at these costates, from costate_lanes
      Scratch<double>& s = scratch_;
      terms.torque_gradient(i, u, rho, s.w);
      F.head(terms.n()) = s.w + mu_all_.col(i);
      s.gq = -gq_all_.col(i);
      s.gv = -gv_all_.col(i);
      terms.close_stage(i, q, v, u, d, rho, lmd_next, s.gq, s.gv, hq, hv, F, state, s.frame);
      return;
    }
  }
  dynamics_stamp_.require(i, ev, "the Hamiltonian");
  if constexpr (kDerivativeLanes) {
    if (state) {
      // the derivative matrices from derivative_lanes
      lanes_stamp_.require(i, ev, "the Hamiltonian's derivatives");
      const Derivatives& D = derivatives_[static_cast<size_t>(i)];
      Scratch<double>& s = scratch_;
      terms.torque_gradient(i, u, rho, s.w);
      s.gq.noalias() = D.da_dq.transpose() * gmm_next;
      s.gv.noalias() = D.da_dv.transpose() * gmm_next;
      auto hu = F.head(terms.n());
      hu = s.w;
      hu.noalias() += D.Minv.transpose() * gmm_next;
      terms.close_stage(i, q, v, u, d, rho, lmd_next, s.gq, s.gv, hq, hv, F, state, s.frame);
      return;
    }
  }
  stage_hamiltonian<double>(terms, i, stage_[static_cast<size_t>(i)], scratch_, q, v, u, d, rho, lmd_next,
                            gmm_next, hq, hv, F, state);
}

template <DerivativeMode M, bool Lanes>
void FdStages<M, Lanes>::hamiltonian(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn,
                                     DualIn u, DualIn d, DualIn rho, DualIn lmd_next, DualIn gmm_next, DualOut hq,
                                     DualOut hv, DualOut F, bool state) {
  require_dual();
  dual_stamp_.require(i, ev, "the Hamiltonian");
  stage_hamiltonian<Dual>(terms, i, dual_stage_[static_cast<size_t>(i)], dual_scratch_, q, v, u, d, rho, lmd_next,
                          gmm_next, hq, hv, F, state);
}

template <DerivativeMode M, bool Lanes> std::size_t FdStages<M, Lanes>::workspace_bytes() const {
  std::size_t b = stage_.capacity() * sizeof(Data) + heap_bytes(lanes_) +
                  derivatives_.capacity() * sizeof(Derivatives);
  for (const Data& d : stage_) b += heap_bytes(d);
  b += dual_stage_.capacity() * sizeof(DataTpl<Dual>);
  for (const DataTpl<Dual>& d : dual_stage_) b += heap_bytes(d);
  for (const Derivatives& d : derivatives_) b += 3 * static_cast<std::size_t>(d.Minv.size()) * sizeof(double);
  for (const MatX<double>* x : {&mu_all_, &gq_all_, &gv_all_}) b += static_cast<std::size_t>(x->size()) * sizeof(double);
  return b;
}

template class FdStages<DerivativeMode::kMatrix, false>;
template class FdStages<DerivativeMode::kMatrix, true>;
template class FdStages<DerivativeMode::kAdjoint, false>;
template class FdStages<DerivativeMode::kAdjoint, true>;

}  // namespace idmpc
