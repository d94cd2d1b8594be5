#pragma once
/// @file id_stages.hpp
/// @brief The inverse-dynamics problem's stages (formulations.md §ID, input = acceleration a_i; paper eqs.
/// 12, 16, 18, 22–25):
///   u_i = ID(q_i, v_i, a_i) − d̂,  w_i = ∂(L + ρᵀ(s∘c))/∂u,
///   ∂H/∂a = γ_{i+1} + Q_a a + M w,  ∂H/∂q = ∂L/∂q + (∂ID/∂q)ᵀw,  ∂H/∂v = ∂L/∂v + λ_{i+1} + (∂ID/∂v)ᵀw.
///
/// Policies: M = kAdjoint takes the three products by one reverse RNEA sweep (O(n)); M = kMatrix
/// from ∂ID/∂q, ∂ID/∂v and M of one RNEA-derivatives pass (O(n²), the paper's way). Lanes: the
/// rollout does not depend on the stage dynamics, so once it has run, kStageLanes stages run at
/// once — their RNEA (or its derivatives) and the products — and a stage keeps only its three
/// products; without lanes each stage keeps its RNEA pass (adjoint) or its derivative matrices,
/// as every stage does in dual numbers (exact products, reserve_dual).

#include "idmpc/ocp/stage_model.hpp"
#include "idmpc/spatial/pack.hpp"

namespace idmpc {

template <DerivativeMode M, bool Lanes> class IdStages final : public StageModel {
 public:
  /// @param m multipliers per stage (those of the torque limits and of the passive torques)
  IdStages(const Model& model, int N, int m);

  std::unique_ptr<StageModel> clone() const override { return std::make_unique<IdStages>(*this); }
  void dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) override;
  void at_states(const StageTerms& terms, Evaluation ev, StageTrajectories& x) override;
  void at_costates(const StageTerms& terms, Evaluation ev, StageTrajectories& x) override {
    at_states(terms, ev, x);
  }
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

  /// a stage's scratch vectors in one scalar type
  template <typename S> struct Scratch {
    VecX<S> w, gq, gv, la;
    StageTerms::FrameScratch<S> frame;  ///< the frame cost's kinematics
    explicit Scratch(int n = 0) : w(VecX<S>::Zero(n)), gq(w), gv(w), la(w) {}
  };

  // one stage by itself, in scalar S, keeping its RNEA pass (adjoint) or derivatives (matrix)
  // in data: u = ID(q, v, a) − d̂; and F, hq, hv of its Hamiltonian from them
  template <typename S> void stage_dynamics(const StageTerms& terms, DataTpl<S>& data,
                                            const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                                            const Eigen::Ref<const VecX<S>>& a, Eigen::Ref<VecX<S>> u);
  template <typename S>
  void stage_hamiltonian(const StageTerms& terms, int i, DataTpl<S>& data, Scratch<S>& s,
                         const Eigen::Ref<const VecX<S>>& q, const Eigen::Ref<const VecX<S>>& v,
                         const Eigen::Ref<const VecX<S>>& a, const Eigen::Ref<const VecX<S>>& u,
                         const Eigen::Ref<const VecX<S>>& d, const Eigen::Ref<const VecX<S>>& rho,
                         const Eigen::Ref<const VecX<S>>& lmd_next, const Eigen::Ref<const VecX<S>>& gmm_next,
                         Eigen::Ref<VecX<S>> hq, Eigen::Ref<VecX<S>> hv, Eigen::Ref<VecX<S>> F, bool state);

  // stages i0 … i0 + count − 1 in lanes: x.u out, the products kept
  void lanes(const StageTerms& terms, Evaluation ev, int i0, int count, StageTrajectories& x);

  std::vector<Data> stage_;               ///< without lanes: each stage's RNEA pass or derivatives
  Data single_;                           ///< with lanes: RNEA of a stage by itself (dynamics)
  detail::StageStamps stamp_;             ///< the evaluation of each stage's dynamics
  DataTpl<StagePack> lanes_;              ///< workspace of the stages in lanes
  VecX<StagePack> ql_, vl_, al_, wl_, rl_, ul_;  ///< q, v, a, w, ρ, u in lanes
  MatX<double> gq_all_, gv_all_, Mw_all_; ///< with lanes: (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M w, n × N
  Scratch<double> scratch_;               ///< stage scratch
  std::vector<DataTpl<Dual>> dual_stage_; ///< reserve_dual: each stage's workspace in dual numbers
  detail::StageStamps dual_stamp_;        ///< the evaluation of each stage's dual RNEA
  Scratch<Dual> dual_scratch_;
  int N_;
};

extern template class IdStages<DerivativeMode::kMatrix, false>;
extern template class IdStages<DerivativeMode::kMatrix, true>;
extern template class IdStages<DerivativeMode::kAdjoint, false>;
extern template class IdStages<DerivativeMode::kAdjoint, true>;

}  // namespace idmpc
