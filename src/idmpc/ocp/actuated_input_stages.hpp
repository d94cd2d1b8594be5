#pragma once
/// @file actuated_input_stages.hpp
/// @brief The forward-dynamics stages of an under-actuated model (formulations.md
/// §Under-actuation): the input is the actuators' torques u (n_u = Model::n_actuated()), and the
/// joints see τ = Sᵀu, S the selection of the actuated rows, the passive joints' torque zero.
/// Then a = FD(q, v, Sᵀu + d̂) and ∂H/∂u = S ∂H/∂τ: the fully actuated stage's input rows at the
/// actuated joints. This stage model wraps the fully actuated one (whatever its mode and lanes)
/// and gathers those rows; the joint torques it is given (StageTrajectories::u) are Sᵀu already
/// (Shooting scatters the input).

#include "idmpc/ocp/stage_model.hpp"

namespace idmpc {

class ActuatedInputStages final : public StageModel {
 public:
  /// @param stages the fully actuated FD stages of `model`; @param m bounded joints.
  ActuatedInputStages(std::unique_ptr<StageModel> stages, const Model& model, int m);
  ActuatedInputStages(const ActuatedInputStages& o);

  std::unique_ptr<StageModel> clone() const override { return std::make_unique<ActuatedInputStages>(*this); }
  void dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) override {
    stages_->dynamics(terms, ev, i, q, v, input, output);
  }
  void at_states(const StageTerms& terms, Evaluation ev, StageTrajectories& x) override {
    stages_->at_states(terms, ev, x);
  }
  void at_costates(const StageTerms& terms, Evaluation ev, StageTrajectories& x) override {
    stages_->at_costates(terms, ev, x);
  }
  /// @brief F (size n_u + 2m): the wrapped stage's F at the actuated rows, then its 2m rows.
  void hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In a, In u, In d, In rho,
                   In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) override;
  std::size_t workspace_bytes() const override;
  void dynamics(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn input,
                DualOut output) override {
    stages_->dynamics(terms, ev, i, q, v, input, output);
  }
  void hamiltonian(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn a, DualIn u, DualIn d,
                   DualIn rho, DualIn lmd_next, DualIn gmm_next, DualOut hq, DualOut hv, DualOut F,
                   bool state) override;
  void reserve_dual(const Model& model) override;

 private:
  // F ← the actuated rows of `full`, then its last 2m rows
  template <typename S> void gather(const VecX<S>& full, Eigen::Ref<VecX<S>> F) const;

  std::unique_ptr<StageModel> stages_;
  std::vector<int> actuated_;
  VecX<double> full_;      ///< the wrapped stage's F (n + 2m)
  VecX<Dual> dual_full_;   ///< … in dual numbers (reserve_dual)
};

}  // namespace idmpc
