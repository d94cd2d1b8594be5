#include "idmpc/ocp/problem.hpp"

#include <cmath>
#include <stdexcept>

#include "idmpc/dynamics/crba.hpp"
#include "idmpc/ocp/actuated_input_stages.hpp"
#include "idmpc/ocp/fd_stages.hpp"
#include "idmpc/ocp/id_stages.hpp"

namespace idmpc {

std::string to_string(Formulation f) { return f == Formulation::kForwardDynamics ? "fd" : "id"; }
std::string to_string(DerivativeMode d) { return d == DerivativeMode::kMatrix ? "matrix" : "adjoint"; }

Formulation parse_formulation(const std::string& s) {
  if (s == "fd") return Formulation::kForwardDynamics;
  if (s == "id") return Formulation::kInverseDynamics;
  throw std::invalid_argument("unknown formulation '" + s + "': expected 'fd' or 'id'");
}

DerivativeMode parse_derivative_mode(const std::string& s) {
  if (s == "matrix") return DerivativeMode::kMatrix;
  if (s == "adjoint") return DerivativeMode::kAdjoint;
  throw std::invalid_argument("unknown derivative mode '" + s + "': expected 'matrix' or 'adjoint'");
}

int OcpProblem::checked_n(const std::shared_ptr<const Model>& model) {
  if (!model) throw std::invalid_argument("optimal control problem: expected a model, got none");
  return model->n;
}

OcpProblem::OcpProblem(std::shared_ptr<const Model> model, Formulation formulation, DerivativeMode mode,
                       QuadraticCost cost, int N, const TorqueLimits& limits)
    : terms_(std::move(model), std::move(cost), limits, N, mode == DerivativeMode::kMatrix,
             formulation == Formulation::kInverseDynamics),
      formulation_(formulation),
      mode_(mode),
      N_(N) {
  if (N < 1) throw std::invalid_argument("horizon steps N must be at least 1, got " + std::to_string(N));
  const Model& m = terms_.model();
  if (m.n_actuated() == 0) {
    throw std::invalid_argument("model '" + m.name + "' has no actuated joint: there is nothing to control");
  }
  if (formulation_ == Formulation::kForwardDynamics) {
    for (int j : m.actuated_joints) {
      if (!(terms_.cost().weights().R[j] > 0)) {
        throw std::invalid_argument("the forward-dynamics problem needs R > 0 on every actuated joint");
      }
    }
  }
  stages_ = make_stages();
}

OcpProblem::OcpProblem(const OcpProblem& o)
    : terms_(o.terms_),
      formulation_(o.formulation_),
      mode_(o.mode_),
      N_(o.N_),
      lanes_(o.lanes_),
      dual_(o.dual_),
      stages_(o.stages_->clone()),
      evaluations_(o.evaluations_) {}

OcpProblem& OcpProblem::operator=(const OcpProblem& o) {
  if (this != &o) *this = OcpProblem(o);
  return *this;
}

VecX<double> OcpProblem::input_block_diagonal(double Tf) const {
  if (!(Tf > 0) || !std::isfinite(Tf)) {
    throw std::invalid_argument("the horizon T_f must be positive and finite, got " + std::to_string(Tf));
  }
  const Model& model = terms_.model();
  const OcpWeights& w = weights();
  const int n = model.n;
  Data data(model, DataParts::rnea() | DataParts::crba());
  const MatX<double> M = crba(model, data, cost().q_ref());
  const double dtau = Tf / N_;
  const VecX<double> c = dtau * (w.Qq * (Tf * Tf * Tf / 3) + w.Qv * Tf);
  if (formulation_ == Formulation::kInverseDynamics) {
    VecX<double> C = (M.transpose() * w.R.asDiagonal() * M).diagonal() + c;
    if (w.Qa.size() == n) C += w.Qa;
    return C;
  }
  const MatX<double> Minv = M.ldlt().solve(MatX<double>::Identity(n, n));
  return w.R + Minv.cwiseAbs2().transpose() * c;
}

void OcpProblem::cap_limit_rows(double Tf) { terms_.bounds().cap_scale(input_block_diagonal(Tf)); }

void OcpProblem::scale_passive_rows(double Tf) {
  if (terms_.n_e() == 0) return;
  const Model& model = terms_.model();
  const VecX<double> C = input_block_diagonal(Tf);
  Data data(model, DataParts::rnea() | DataParts::crba());
  const MatX<double> M = crba(model, data, cost().q_ref());
  double sum = 0;
  for (int j : model.unactuated_joints) sum += C[j] / M(j, j);
  terms_.set_passive_scale(sum / static_cast<double>(model.unactuated_joints.size()));
}

void OcpProblem::set_stages_in_lanes(bool on) {
  if (on == lanes_) return;
  lanes_ = on;
  stages_ = make_stages();
  if (dual_) stages_->reserve_dual(terms_.model());
}

std::unique_ptr<LocalModel> OcpProblem::make_local_model() const {
  if (formulation_ == Formulation::kForwardDynamics) return std::make_unique<FdLocalModel>(terms_);
  return std::make_unique<IdLocalModel>(terms_);
}

std::unique_ptr<StageModel> OcpProblem::make_stages() const {
  using D = DerivativeMode;
  const Model& model = terms_.model();
  if (formulation_ == Formulation::kForwardDynamics) {
    std::unique_ptr<StageModel> fd;
    if (mode_ == D::kMatrix) {
      fd = lanes_ ? std::unique_ptr<StageModel>(std::make_unique<FdStages<D::kMatrix, true>>(model, N_))
                  : std::make_unique<FdStages<D::kMatrix, false>>(model, N_);
    } else {
      fd = lanes_ ? std::unique_ptr<StageModel>(std::make_unique<FdStages<D::kAdjoint, true>>(model, N_))
                  : std::make_unique<FdStages<D::kAdjoint, false>>(model, N_);
    }
    // under-actuated: the actuators' torques are the input
    if (model.under_actuated()) return std::make_unique<ActuatedInputStages>(std::move(fd), model, terms_.m());
    return fd;
  }
  // ID: the multipliers ρ of the limits and ν of the passive torques
  const int m = terms_.m() + terms_.n_e();
  if (mode_ == D::kMatrix) {
    if (lanes_) return std::make_unique<IdStages<D::kMatrix, true>>(model, N_, m);
    return std::make_unique<IdStages<D::kMatrix, false>>(model, N_, m);
  }
  if (lanes_) return std::make_unique<IdStages<D::kAdjoint, true>>(model, N_, m);
  return std::make_unique<IdStages<D::kAdjoint, false>>(model, N_, m);
}

}  // namespace idmpc
