#pragma once
/// @file id_stages.hpp
/// @brief The inverse-dynamics problem's stages (DESIGN §4, input = acceleration a_i; paper eqs.
/// 12, 16, 18, 22–25):
///   u_i = ID(q_i, v_i, a_i) − d̂,  w_i = ∂(L + ρᵀ(s∘c))/∂u,
///   ∂H/∂a = γ_{i+1} + Q_a a + M w,  ∂H/∂q = ∂L/∂q + (∂ID/∂q)ᵀw,  ∂H/∂v = ∂L/∂v + λ_{i+1} + (∂ID/∂v)ᵀw.
///
/// Policies: M = kAdjoint takes the three products by one reverse RNEA sweep (O(n)); M = kMatrix
/// from ∂ID/∂q, ∂ID/∂v and M of one RNEA-derivatives pass (O(n²), the paper's way). Lanes: the
/// rollout does not depend on the stage dynamics, so once it has run, kStageLanes stages run at
/// once — their RNEA (or its derivatives) and the products — and a stage keeps only its three
/// products; without lanes each stage keeps its RNEA pass (adjoint) or its derivative matrices.

#include "idmpc/ocp/stage_model.hpp"
#include "idmpc/spatial/pack.hpp"

namespace idmpc {

template <DerivativeMode M, bool Lanes> class IdStages final : public StageModel {
 public:
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

 private:
  static constexpr bool kMatrix = M == DerivativeMode::kMatrix;

  // stages i0 … i0 + count − 1 in lanes: x.u out, the products kept
  void lanes(const StageTerms& terms, Evaluation ev, int i0, int count, StageTrajectories& x);

  std::vector<Data> stage_;               ///< without lanes: each stage's RNEA pass or derivatives
  Data single_;                           ///< with lanes: RNEA of a stage by itself (dynamics)
  detail::StageStamps stamp_;             ///< the evaluation of each stage's dynamics
  DataTpl<StagePack> lanes_;              ///< workspace of the stages in lanes
  VecX<StagePack> ql_, vl_, al_, wl_, rl_, ul_;  ///< q, v, a, w, ρ, u in lanes
  MatX<double> gq_all_, gv_all_, Mw_all_; ///< with lanes: (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M w, n × N
  Vec w_, gq_, gv_, la_;                  ///< stage scratch
};

extern template class IdStages<DerivativeMode::kMatrix, false>;
extern template class IdStages<DerivativeMode::kMatrix, true>;
extern template class IdStages<DerivativeMode::kAdjoint, false>;
extern template class IdStages<DerivativeMode::kAdjoint, true>;

}  // namespace idmpc
