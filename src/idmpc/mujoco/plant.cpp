#include "idmpc/mujoco/plant.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace idmpc::mj {

Plant::Plant(const mjModel* m, const Actuation& actuation) : actuation_(actuation) {
  install_error_handlers();
  m_.reset(mj_copyModel(nullptr, m));
  if (!m_) throw std::runtime_error("MuJoCo could not copy the model");
  if (actuation_.direct) m_->opt.disableflags |= mjDSBL_ACTUATION;
  d_ = make_data(m_.get());
}

std::string Plant::set_control_period(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) {
    throw std::invalid_argument("control period must be positive, got " + std::to_string(dt));
  }
  const double ratio = dt / m_->opt.timestep;
  const double whole = std::round(ratio);
  if (whole >= 1 && std::abs(ratio - whole) <= 1e-9 * whole) {
    substeps_ = static_cast<int>(whole);
    return "";
  }
  std::ostringstream o;
  o << "the model's timestep " << m_->opt.timestep << " s is replaced by the control period " << dt
    << " s (not a whole multiple of it)";
  m_->opt.timestep = dt;
  substeps_ = 1;
  return o.str();
}

void Plant::reset(const VecX<double>& q, const VecX<double>& v) {
  if (q.size() != m_->nq || v.size() != m_->nv) {
    throw std::invalid_argument("initial state has " + std::to_string(q.size()) +
                                " positions, the model has " + std::to_string(m_->nq));
  }
  mj_resetData(m_.get(), d_.get());
  mju_copy(d_->qpos, q.data(), m_->nq);
  mju_copy(d_->qvel, v.data(), m_->nv);
  mj_forward(m_.get(), d_.get());
  contact_steps_ = 0;
  max_contact_force_ = 0;
}

void Plant::apply(const VecX<double>& tau) {
  // a passive joint gets nothing, whatever τ holds there
  if (actuation_.direct) {
    mju_copy(d_->qfrc_applied, tau.data(), m_->nv);
    for (int i : actuation_.passive_dofs) d_->qfrc_applied[i] = 0;
  } else {
    for (int i = 0; i < m_->nv; ++i) {
      const int u = actuation_.actuator_of_dof[i];
      if (u >= 0) d_->ctrl[u] = tau[i] * actuation_.ctrl_per_torque[i];
    }
  }
}

bool Plant::step(const VecX<double>& tau, std::string* reason) { return step(tau, substeps_, tau, reason); }

bool Plant::step(const VecX<double>& tau_before, int switch_at, const VecX<double>& tau_after, std::string* reason) {
  if (switch_at < 0 || switch_at > substeps_) {
    throw std::invalid_argument("Plant::step: the torque switches after " + std::to_string(switch_at) +
                                " substeps, expected 0 to " + std::to_string(substeps_));
  }
  if (!tau_before.allFinite() || !tau_after.allFinite()) {
    if (reason) *reason = "non-finite torque";
    return false;
  }
  apply(switch_at > 0 ? tau_before : tau_after);
  int warnings_before = 0;
  for (int w = 0; w < mjNWARNING; ++w) warnings_before += d_->warning[w].number;
  bool contact = false;
  for (int k = 0; k < substeps_; ++k) {
    if (k == switch_at && k > 0) apply(tau_after);
    mj_step(m_.get(), d_.get());
    for (int c = 0; c < d_->ncon; ++c) {
      mjtNum force[6];
      mj_contactForce(m_.get(), d_.get(), c, force);
      max_contact_force_ = std::max(max_contact_force_, std::abs(force[0]));
      contact = true;
    }
  }
  contact_steps_ += contact;
  int warnings_after = 0;
  for (int w = 0; w < mjNWARNING; ++w) warnings_after += d_->warning[w].number;
  // MuJoCo resets the state on a bad acceleration: that is a divergence, not a new start
  if (warnings_after != warnings_before) {
    if (reason) *reason = "MuJoCo warning during mj_step (e.g. huge or non-finite acceleration)";
    return false;
  }
  if (!q().allFinite() || !v().allFinite()) {
    if (reason) *reason = "non-finite plant state";
    return false;
  }
  return true;
}

}  // namespace idmpc::mj
