#include "idmpc/ocp/actuated_input_stages.hpp"

#include <cassert>

namespace idmpc {

ActuatedInputStages::ActuatedInputStages(std::unique_ptr<StageModel> stages, const Model& model, int m)
    : stages_(std::move(stages)), actuated_(model.actuated_joints), full_(VecX<double>::Zero(model.n + 2 * m)) {
  assert(stages_);
}

ActuatedInputStages::ActuatedInputStages(const ActuatedInputStages& o)
    : StageModel(o), stages_(o.stages_->clone()), actuated_(o.actuated_), full_(o.full_), dual_full_(o.dual_full_) {}

template <typename S> void ActuatedInputStages::gather(const VecX<S>& full, Eigen::Ref<VecX<S>> F) const {
  const auto nu = static_cast<Eigen::Index>(actuated_.size());
  const Eigen::Index rest = F.size() - nu;
  assert(full.size() - rest >= nu);
  for (Eigen::Index k = 0; k < nu; ++k) F[k] = full[actuated_[static_cast<std::size_t>(k)]];
  F.tail(rest) = full.tail(rest);
}

void ActuatedInputStages::hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In a, In u, In d,
                                      In rho, In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) {
  stages_->hamiltonian(terms, ev, i, q, v, a, u, d, rho, lmd_next, gmm_next, hq, hv, full_, state);
  gather<double>(full_, F);
}

void ActuatedInputStages::hamiltonian(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn a,
                                      DualIn u, DualIn d, DualIn rho, DualIn lmd_next, DualIn gmm_next, DualOut hq,
                                      DualOut hv, DualOut F, bool state) {
  require_dual();
  stages_->hamiltonian(terms, ev, i, q, v, a, u, d, rho, lmd_next, gmm_next, hq, hv, dual_full_, state);
  gather<Dual>(dual_full_, F);
}

void ActuatedInputStages::reserve_dual(const Model& model) {
  stages_->reserve_dual(model);
  dual_full_ = VecX<Dual>::Zero(full_.size());
  dual_reserved_ = true;
}

std::size_t ActuatedInputStages::workspace_bytes() const {
  return stages_->workspace_bytes() + static_cast<std::size_t>(full_.size()) * sizeof(double) +
         static_cast<std::size_t>(dual_full_.size()) * sizeof(Dual);
}

}  // namespace idmpc
