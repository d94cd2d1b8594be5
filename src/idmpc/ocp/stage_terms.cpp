#include "idmpc/ocp/stage_terms.hpp"

#include <stdexcept>
#include <string>

#include "idmpc/dynamics/rnea.hpp"

namespace idmpc {
namespace {

const Model& checked(const std::shared_ptr<const Model>& model) {
  if (!model) throw std::invalid_argument("optimal control problem: expected a model, got none");
  return *model;
}

}  // namespace

StageTerms::StageTerms(std::shared_ptr<const Model> model, QuadraticCost cost, const TorqueLimits& limits)
    : model_(std::move(model)),
      cost_(std::move(cost)),
      bounds_(limits, cost_.weights().R, cost_.n()),
      d_hat_(Vec::Zero(checked(model_).n)),
      zero_(Vec::Zero(model_->n)),
      tau_ref_(Vec::Zero(model_->n)),
      u_ref_(Vec::Zero(model_->n)),
      rnea_data_(*model_, DataParts::rnea()) {
  if (cost_.n() != model_->n) {
    throw std::invalid_argument("the costs have " + std::to_string(cost_.n()) + " joints, the model " +
                                std::to_string(model_->n));
  }
  tau_ref_ = rnea(*model_, rnea_data_, cost_.q_ref(), zero_, zero_);
  update_torque_reference();
}

void StageTerms::set_disturbance(const Vec& d_hat) {
  if (d_hat.size() != n() || !d_hat.allFinite()) {
    throw std::invalid_argument("disturbance estimate: expected " + std::to_string(n()) + " finite values, got " +
                                std::to_string(d_hat.size()));
  }
  d_hat_ = d_hat;
  update_torque_reference();
}

void StageTerms::set_target(const Vec& q_ref) {
  cost_.set_target(q_ref);
  tau_ref_ = rnea(*model_, rnea_data_, cost_.q_ref(), zero_, zero_);
  update_torque_reference();
}

void StageTerms::update_torque_reference() {
  // the gravity and spring torque that holds the target, less what the model misses (DESIGN §8, §10)
  u_ref_ = tau_ref_ - d_hat_;
  cost_.set_torque_reference(u_ref_);
}

}  // namespace idmpc
