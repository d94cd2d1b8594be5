#include "idmpc/solver/controller.hpp"

#include <stdexcept>

#include "idmpc/dynamics/rnea.hpp"

namespace idmpc {

Controller::Controller(OcpProblem problem, const CgmresSettings& settings)
    : nlp_(std::move(problem)), solver_(nlp_, settings), data_(nlp_.problem().model()) {
  const int n = nlp_.n();
  for (Vec* x : {&tau_, &a0_hat_, &q_pred_, &v_pred_}) *x = Vec::Zero(n);
}

const VecX<double>& Controller::initialize(In q, In v) {
  solver_.initialize(0.0, q, v);
  failure_.clear();
  // the state is measured now and the torque applies now: no prediction (Δt = 0)
  const auto a0 = solver_.solution().head(n());
  torque_rule(q, v, a0, 0.0);
  if (nlp_.formulation() == Formulation::kInverseDynamics) a0_hat_ = a0;
  return tau_;
}

bool Controller::update(double t, In q, In v) {
  failure_.clear();
  if (!solver_.update(t, q, v)) {
    failure_ = "C/GMRES solution or residual became non-finite or exceeded 1e8";
    return false;
  }
  torque_rule(q, v, a0_hat_, dt());
  if (!tau_.allFinite()) {
    failure_ = "non-finite torque";
    return false;
  }
  // the new solution is the one executed from now on
  if (nlp_.formulation() == Formulation::kInverseDynamics) a0_hat_ = solver_.solution().head(n());
  return true;
}

void Controller::torque_rule(In q, In v, In a0_hat, double dt) {
  const auto U0 = solver_.solution().head(n());
  if (nlp_.formulation() == Formulation::kForwardDynamics) {
    tau_ = U0;
    return;
  }
  // delay-compensated inverse dynamics (paper eqs. 27–28)
  q_pred_ = q + dt * v;
  v_pred_ = v + dt * a0_hat;
  tau_ = rnea(nlp_.problem().model(), data_, q_pred_, v_pred_, U0);
}

}  // namespace idmpc
