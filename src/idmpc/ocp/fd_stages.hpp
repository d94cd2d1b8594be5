#pragma once
/// @file fd_stages.hpp
/// @brief The forward-dynamics problem's stages (formulations.md §FD, input = torque u_i):
///   a_i = FD(q_i, v_i, u_i + d̂),  μ_i = M(q_i)⁻¹γ_{i+1},
///   ∂H/∂u = w + μ,  ∂H/∂q = ∂L/∂q − (∂ID/∂q)ᵀμ,  ∂H/∂v = ∂L/∂v + λ_{i+1} − (∂ID/∂v)ᵀμ
/// with w = ∂(L + ρᵀ(s∘c))/∂u (StageTerms::torque_gradient).
///
/// Policies: M = kAdjoint takes μ through the stage's ABA factorization and the products by one
/// reverse RNEA sweep at (q, v, a) (O(n)); M = kMatrix builds ∂q̈/∂q, ∂q̈/∂v and M⁻¹ (O(n²),
/// the paper's way; stage 0, whose state derivatives are never used, takes μ alone by the
/// adjoint way). Lanes: with kMatrix, the derivatives of kStageLanes stages per ABA once the
/// rollout has run (they depend on each stage's state and torque only); with kAdjoint, at given
/// costates (multiple shooting), whole stages per ABA.
///
/// Each stage's workspace holds the ABA factorization and what its mode adds: the adjoint
/// sweep's O(n) buffers, or the derivative matrices (3 n×n in lanes, where the derivatives'
/// scratch is the lanes' alone; 6 n×n and the dense M⁻¹'s 6×n blocks otherwise). In dual
/// numbers (exact products, reserve_dual) every stage has such a workspace without lanes.

#include "idmpc/ocp/stage_model.hpp"
#include "idmpc/spatial/pack.hpp"

namespace idmpc {

template <DerivativeMode M, bool Lanes> class FdStages final : public StageModel {
 public:
  FdStages(const Model& model, int N);

  std::unique_ptr<StageModel> clone() const override { return std::make_unique<FdStages>(*this); }
  void dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) override;
  void at_states(const StageTerms& terms, Evaluation ev, StageTrajectories& x) override;
  void at_costates(const StageTerms& terms, Evaluation ev, StageTrajectories& x) override;
  void hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In a, In u, In d, In rho,
                   In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) override;
  std::size_t workspace_bytes() const override;
  void dynamics(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn input,
                DualOut output) override;
  void hamiltonian(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn a, DualIn u, DualIn d,
                   DualIn rho, DualIn lmd_next, DualIn gmm_next, DualOut hq, DualOut hv, DualOut F,
                   bool state) override;
  void reserve_dual(const Model& model) override;

 private:
  static constexpr bool kMatrix = M == DerivativeMode::kMatrix;
  static constexpr bool kDerivativeLanes = kMatrix && Lanes;
  static constexpr bool kCostateLanes = !kMatrix && Lanes;

  /// ∂q̈/∂q, ∂q̈/∂v and M⁻¹ of one stage, from the lanes
  struct Derivatives {
    MatX<double> da_dq, da_dv, Minv;
  };

  // the derivatives of stages i0 … i0 + count − 1 in lanes, into derivatives_
  void derivative_lanes(const StageTerms& terms, Evaluation ev, int i0, int count, const StageTrajectories& x);
  // whole stages i0 … i0 + count − 1 at the costates x.gmm in lanes: a out, the products kept
  void costate_lanes(const StageTerms& terms, Evaluation ev, int i0, int count, StageTrajectories& x);

  /// a stage's scratch vectors in one scalar type
  template <typename S> struct Scratch {
    VecX<S> tau, w, gq, gv;
    StageTerms::FrameScratch<S> frame;  ///< the frame cost's kinematics
    explicit Scratch(int n = 0) : tau(VecX<S>::Zero(n)), w(tau), gq(tau), gv(tau) {}
  };

  // one stage by itself, in scalar S: a = FD(q, v, u + d̂); and F, hq, hv of its Hamiltonian
  // from that ABA pass (matrix mode: the derivative matrices, stage 0 by the adjoint way)
  template <typename S> void stage_dynamics(const StageTerms& terms, DataTpl<S>& data, Scratch<S>& s,
                                            const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                                            const Eigen::Ref<const VecX<S>>& u, Eigen::Ref<VecX<S>> a);
  template <typename S>
  void stage_hamiltonian(const StageTerms& terms, int i, DataTpl<S>& data, Scratch<S>& s,
                         const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                         const Eigen::Ref<const VecX<S>>& u, const Eigen::Ref<const VecX<S>>& d,
                         const Eigen::Ref<const VecX<S>>& rho, const Eigen::Ref<const VecX<S>>& lmd_next,
                         const Eigen::Ref<const VecX<S>>& gmm_next, Eigen::Ref<VecX<S>> hq, Eigen::Ref<VecX<S>> hv,
                         Eigen::Ref<VecX<S>> F, bool state);

  std::vector<Data> stage_;            ///< each stage's ABA and what its mode adds
  std::vector<Derivatives> derivatives_;  ///< kDerivativeLanes: each stage's, from the lanes
  detail::StageStamps dynamics_stamp_;    ///< the evaluation of each stage's ABA
  detail::StageStamps lanes_stamp_;       ///< … of its derivatives or products from the lanes
  DataTpl<StagePack> lanes_;              ///< workspace of the stages in lanes
  VecX<StagePack> ql_, vl_, tl_, gl_;     ///< q, v, torque, γ_{i+1} (then μ) in lanes
  MatX<double> mu_all_, gq_all_, gv_all_; ///< kCostateLanes: μ, (∂ID/∂q)ᵀμ, (∂ID/∂v)ᵀμ, n × N
  Scratch<double> scratch_;               ///< stage scratch
  std::vector<DataTpl<Dual>> dual_stage_; ///< reserve_dual: each stage's workspace in dual numbers
  detail::StageStamps dual_stamp_;        ///< the evaluation of each stage's dual ABA
  Scratch<Dual> dual_scratch_;
};

extern template class FdStages<DerivativeMode::kMatrix, false>;
extern template class FdStages<DerivativeMode::kMatrix, true>;
extern template class FdStages<DerivativeMode::kAdjoint, false>;
extern template class FdStages<DerivativeMode::kAdjoint, true>;

}  // namespace idmpc
