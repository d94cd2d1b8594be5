#include "idmpc/solver/controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "idmpc/dynamics/rnea.hpp"
#include "idmpc/model/checks.hpp"

namespace idmpc {

namespace {

// the horizon's problem of `settings` with the models and weights `setup` chose for them
OcpProblem make_problem(const HorizonSetup& setup, const ControllerSettings& s) {
  const int n = setup.horizon_model->n;
  OcpWeights w = setup.weights;
  if (w.Qa.size() == 0) w.Qa = VecX<double>::Zero(n);
  TorqueLimits limits;
  if (s.limits_in_horizon && s.torque_lower.size() == n &&
      (s.torque_lower.array().isFinite() || s.torque_upper.array().isFinite()).any()) {
    limits = TorqueLimits{s.torque_lower, s.torque_upper};
  }
  OcpProblem problem(setup.horizon_model, s.formulation, s.derivatives, std::move(w), s.q_ref, s.N, limits);
  problem.cap_limit_rows(s.cgmres.Tf);  // the limits' rows no larger than the input's (torque_limits.hpp)
  problem.scale_passive_rows(s.cgmres.Tf);  // ID's passive-torque rows at the input's (under-actuated)
  problem.set_frame_target(s.frame_target);
  problem.set_terminal_weight(setup.terminal_weight);
  if (s.frame_reference) problem.set_frame_trajectory(s.frame_reference);
  if (s.joint_reference) problem.set_joint_trajectory(s.joint_reference);
  return problem;
}

// the choices of horizon_setup.hpp for `settings` on `model`, the settings checked first
std::shared_ptr<const HorizonSetup> checked_setup(const std::shared_ptr<const Model>& model,
                                                  const ControllerSettings& settings) {
  validate(settings);
  if (!model) throw std::invalid_argument("controller: no model given");
  return std::make_shared<const HorizonSetup>(setup_horizon(*model, settings));
}

// the solver `setup` chose for `settings` (their own, or "auto" resolved) over `problem`
std::unique_ptr<MpcSolver> make_solver(OcpProblem problem, const ControllerSettings& s, const HorizonSetup& setup) {
  if (setup.solver == SolverKind::kRiccati) {
    return std::make_unique<RiccatiSolver>(std::move(problem), s.cgmres.Tf, s.cgmres.dt, s.riccati);
  }
  auto solver = std::make_unique<CgmresMpc>(std::move(problem), s.cgmres);
  solver->shooting().set_stage_batching(s.simd_stages);
  return solver;
}

}  // namespace

void validate(const ControllerSettings& s) {
  // bounded before anything is sized from it
  if (s.N < 1 || s.N > kMaxHorizonStages) {
    throw std::invalid_argument("controller settings: N must be from 1 to " + std::to_string(kMaxHorizonStages) +
                                " horizon stages, got " + std::to_string(s.N));
  }
  s.cgmres.validate();  // Δt and T_f, which both solvers use
  if (!(s.plant_step >= 0) || !std::isfinite(s.plant_step)) {
    throw std::invalid_argument("controller settings: plant_step must be finite and non-negative [s], got " +
                                std::to_string(s.plant_step));
  }
}

Controller::Controller(std::shared_ptr<const Model> model, const ControllerSettings& settings)
    : Controller(settings, checked_setup(model, settings)) {}

Controller::Controller(const ControllerSettings& settings, std::shared_ptr<const HorizonSetup> setup)
    : Controller(make_solver(make_problem(*setup, settings), settings, *setup), setup->plant_model) {
  setup_ = std::move(setup);
  const int n = this->n();
  if (settings.torque_lower.size() == n) {
    if (settings.limits_in_horizon) {
      set_torque_limits(settings.torque_lower, settings.torque_upper);
    } else {
      // the horizon is unconstrained: only the clamp
      check_and_set_clamp(settings.torque_lower, settings.torque_upper, false);
    }
  }
  set_disturbance_observer(settings.observer_time_constant);
}

Controller::Controller(OcpProblem problem, const CgmresSettings& settings, std::shared_ptr<const Model> plant_model)
    : Controller(std::make_unique<CgmresMpc>(std::move(problem), settings), std::move(plant_model)) {}

Controller::Controller(std::unique_ptr<MpcSolver> solver, std::shared_ptr<const Model> plant_model)
    : solver_(solver ? std::move(solver) : throw std::invalid_argument("controller: no solver given")),
      plant_model_(plant_model ? std::move(plant_model) : solver_->problem().model_ptr()),
      data_(*plant_model_) {
  if (plant_model_->n != n()) {
    throw std::invalid_argument("the plant model has " + std::to_string(plant_model_->n) + " joints, the problem " +
                                std::to_string(n()));
  }
  const int n = this->n();
  for (Vec* x : {&tau_, &tau_cmd_, &a0_hat_, &q_pred_, &v_pred_, &q_meas_, &v_meas_, &a0_rule_, &q_prev_, &v_prev_,
                 &tau_last_, &tau_pending_, &d_hat_, &a_meas_}) {
    *x = Vec::Zero(n);
  }
  // the clamp: the horizon's bounds where it has them
  lower_ = Vec::Constant(n, -std::numeric_limits<double>::infinity());
  upper_ = Vec::Constant(n, std::numeric_limits<double>::infinity());
  const TorqueBounds& b = problem().torque_bounds();
  for (int k = 0; k < b.m(); ++k) {
    const int j = b.joints()[static_cast<size_t>(k)];
    lower_[j] = b.middle()[k] - b.half_range()[k];
    upper_[j] = b.middle()[k] + b.half_range()[k];
  }
}

namespace {
CgmresMpc* as_cgmres(MpcSolver& s) {
  if (s.kind() != SolverKind::kCgmres) {
    throw std::logic_error("controller: the solver is '" + to_string(s.kind()) + "', not C/GMRES");
  }
  return static_cast<CgmresMpc*>(&s);
}
}  // namespace

Shooting& Controller::nlp() { return as_cgmres(*solver_)->shooting(); }
const Shooting& Controller::nlp() const { return as_cgmres(*solver_)->shooting(); }
Cgmres& Controller::cgmres() { return as_cgmres(*solver_)->cgmres(); }
const Cgmres& Controller::cgmres() const { return as_cgmres(*solver_)->cgmres(); }

void Controller::set_torque_limits(const Vec& lower, const Vec& upper) { check_and_set_clamp(lower, upper, true); }

void Controller::check_and_set_clamp(const Vec& lower, const Vec& upper, bool match_horizon) {
  const int n = this->n();
  if (lower.size() != n || upper.size() != n) {
    throw std::invalid_argument("torque limits have " + std::to_string(lower.size()) + " and " +
                                std::to_string(upper.size()) + " entries, expected " + std::to_string(n));
  }
  const Model& model = *plant_model_;
  auto joint = [&](int j) {
    return j < static_cast<int>(model.joint_names.size()) ? "'" + model.joint_names[static_cast<size_t>(j)] + "'"
                                                          : std::to_string(j);
  };
  for (int j = 0; j < n; ++j) {
    if (std::isnan(lower[j]) || std::isnan(upper[j]) || !(lower[j] < upper[j])) {
      throw std::invalid_argument("torque limits of joint " + joint(j) + ": expected lower < upper, got [" +
                                  std::to_string(lower[j]) + ", " + std::to_string(upper[j]) + "]");
    }
  }
  if (match_horizon) {
    // where the horizon bounds a joint, the clamp lies within its range (the same, or tighter)
    const TorqueBounds& b = problem().torque_bounds();
    for (int k = 0; k < b.m(); ++k) {
      const int j = b.joints()[static_cast<size_t>(k)];
      const double lo = b.middle()[k] - b.half_range()[k], hi = b.middle()[k] + b.half_range()[k];
      const double tol = 1e-12 * std::max(1.0, std::max(std::abs(lo), std::abs(hi)));
      if (lower[j] < lo - tol || upper[j] > hi + tol) {
        throw std::invalid_argument("torque limits of joint " + joint(j) + ": [" + std::to_string(lower[j]) + ", " +
                                    std::to_string(upper[j]) + "] reach beyond the horizon's bounds [" +
                                    std::to_string(lo) + ", " + std::to_string(hi) + "]");
      }
    }
  }
  lower_ = lower;
  upper_ = upper;
}

void Controller::set_target(const Vec& q_ref) { problem().set_target(q_ref); }

void Controller::set_disturbance_observer(double time_constant) {
  if (!(time_constant >= 0) || !std::isfinite(time_constant)) {
    throw std::invalid_argument("disturbance observer: time constant must be >= 0 and finite, got " +
                                std::to_string(time_constant));
  }
  observer_time_constant_ = time_constant;
}

void Controller::observe(In q, In v, double interval, In tau_applied) {
  const double dt = interval;
  if (observer_time_constant_ > 0 && have_previous_) {
    // the torque the model misses over the last interval: model torque at the measured
    // acceleration minus what the plant applied
    a_meas_ = (v - v_prev_) / dt;
    const double beta = std::min(1.0, dt / observer_time_constant_);
    const Vec& tau_model = rnea(*plant_model_, data_, q_prev_, v_prev_, a_meas_);
    for (int j = 0; j < n(); ++j) {
      const double raw = tau_model[j] - tau_applied[j];
      // bounded by what the actuator could counter: a blown-up measurement cannot wind it up
      const double bound = std::max(std::abs(lower_[j]), std::abs(upper_[j]));
      d_hat_[j] = std::clamp(d_hat_[j] + beta * (raw - d_hat_[j]), -bound, bound);
    }
    if (d_hat_.allFinite()) problem().set_disturbance(d_hat_);
  }
  q_prev_ = q;
  v_prev_ = v;
  have_previous_ = true;
}

const VecX<double>& Controller::initialize(In q, In v) {
  IDMPC_CHECK_ARGUMENT(q.size() == n() && v.size() == n(), "Controller::initialize: q and v must have size n");
  failure_.clear();
  have_previous_ = false;
  d_hat_.setZero();
  problem().set_disturbance(d_hat_);
  start_residual_ = std::numeric_limits<double>::quiet_NaN();
  try {
    solver_->initialize(0.0, q, v);
    start_residual_ = solver_->residual_norm();
  } catch (const std::runtime_error& e) {
    // a non-finite start is a divergence at t = 0, reported like any other
    failure_ = e.what();
    tau_cmd_.setConstant(std::numeric_limits<double>::quiet_NaN());
    tau_.setZero();
    return tau_;
  }
  // the state is measured now and the torque applies now: no prediction (Δt = 0)
  const Vec& a0 = solver_->first_input();
  torque_rule(q, v, a0, 0.0);
  if (problem().formulation() == Formulation::kInverseDynamics) a0_hat_ = a0;
  if (!tau_cmd_.allFinite()) {
    failure_ = "initialization: non-finite torque";
    tau_.setZero();
  }
  tau_pending_ = tau_;  // applied over [0, Δt)
  return tau_;
}

bool Controller::update(double t, In q, In v) {
  IDMPC_CHECK_ARGUMENT(q.size() == n() && v.size() == n(), "Controller::update: q and v must have size n");
  failure_.clear();
  observe(q, v, dt(), tau_last_);
  if (!solver_->update(t, q, v)) {
    failure_ = solver_->failure();
    return false;
  }
  return finish_update(q, v);
}

bool Controller::update(double t, In q, In v, double interval, In tau_applied) {
  IDMPC_CHECK_ARGUMENT(q.size() == n() && v.size() == n() && tau_applied.size() == n(),
                       "Controller::update: q, v and tau_applied must have size n");
  IDMPC_CHECK_ARGUMENT(interval > 0 && std::isfinite(interval), "Controller::update: interval must be positive");
  failure_.clear();
  observe(q, v, interval, tau_applied);
  if (!solver_->update(t, q, v)) {
    failure_ = solver_->failure();
    return false;
  }
  return finish_update(q, v);
}

bool Controller::finish_update(In q, In v) {
  torque_rule(q, v, a0_hat_, dt());
  if (!tau_cmd_.allFinite()) {
    failure_ = "non-finite torque";
    return false;
  }
  q_meas_ = q;
  v_meas_ = v;
  a0_rule_ = a0_hat_;
  // the new solution is the one executed from now on
  if (problem().formulation() == Formulation::kInverseDynamics) a0_hat_ = solver_->first_input();
  // the torque of the current period [t, t + Δt) is the one this update's successor observes
  tau_last_ = tau_pending_;
  tau_pending_ = tau_;
  return true;
}

bool Controller::aim(double delay) {
  IDMPC_CHECK_ARGUMENT(delay >= 0 && std::isfinite(delay), "Controller::aim: delay must be >= 0 and finite");
  failure_.clear();
  torque_rule(q_meas_, v_meas_, a0_rule_, delay);
  if (!tau_cmd_.allFinite()) {
    failure_ = "non-finite torque";
    return false;
  }
  tau_pending_ = tau_;
  return true;
}

void Controller::torque_rule(In q, In v, In a0_hat, double dt) {
  const Vec& U0 = solver_->first_input();
  if (problem().formulation() == Formulation::kForwardDynamics) {
    tau_cmd_ = U0;
  } else {
    // delay-compensated inverse dynamics (paper eqs. 27–28)
    q_pred_ = q + dt * v;
    v_pred_ = v + dt * a0_hat;
    tau_cmd_ = rnea(*plant_model_, data_, q_pred_, v_pred_, U0) - problem().disturbance();
    // a passive joint has no actuator: its torque is the horizon's constraint, not a command
    for (int j : problem().model().unactuated_joints) tau_cmd_[j] = 0;
  }
  // the plant never receives a torque its actuator cannot give (a non-finite command is a
  // divergence, reported by update)
  tau_ = tau_cmd_.cwiseMax(lower_).cwiseMin(upper_);
}

}  // namespace idmpc
