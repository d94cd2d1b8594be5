#include "idmpc/mujoco/plant.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace idmpc::mj {

Plant::Plant(const mjModel* m, const Actuation& actuation, const HeldJoints& held)
    : actuation_(actuation), held_(held) {
  install_error_handlers();
  m_.reset(mj_copyModel(nullptr, m));
  if (!m_) throw std::runtime_error("MuJoCo could not copy the model");
  if (held_.empty()) {
    for (int i = 0; i < m_->nv; ++i) dof_of_.push_back(i);
    for (int u = 0; u < m_->nu; ++u) actuator_of_.push_back(u);
    if (actuation_.direct) m_->opt.disableflags |= mjDSBL_ACTUATION;
  } else {
    dof_of_ = held_.dof_of;
    actuator_of_ = held_.actuator_of;
    // the held joints' actuators stay; direct torques replace the others, whose force is zero
    if (actuation_.direct) {
      for (const int u : actuator_of_) {
        mju_zero(m_->actuator_gainprm + u * mjNGAIN, mjNGAIN);
        mju_zero(m_->actuator_biasprm + u * mjNBIAS, mjNBIAS);
      }
    }
  }
  d_ = make_data(m_.get());
}

VecX<double> Plant::q() const {
  VecX<double> out(nv());
  for (int i = 0; i < nv(); ++i) out[i] = d_->qpos[m_->jnt_qposadr[m_->dof_jntid[dof_of_[static_cast<std::size_t>(i)]]]];
  return out;
}

VecX<double> Plant::v() const {
  VecX<double> out(nv());
  for (int i = 0; i < nv(); ++i) out[i] = d_->qvel[dof_of_[static_cast<std::size_t>(i)]];
  return out;
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
  o << "the control period " << dt << " s is not a whole multiple of the model's timestep " << m_->opt.timestep
    << " s: the plant steps at " << dt << " s instead (" << (dt < m_->opt.timestep ? "finer" : "coarser") << ")";
  m_->opt.timestep = dt;
  substeps_ = 1;
  return o.str();
}

void Plant::reset(const VecX<double>& q, const VecX<double>& v) {
  if (q.size() != nv() || v.size() != nv()) {
    throw std::invalid_argument("initial state has " + std::to_string(q.size()) + " positions and " +
                                std::to_string(v.size()) + " velocities, the controller's model has " +
                                std::to_string(nv()));
  }
  mj_resetData(m_.get(), d_.get());
  for (int i = 0; i < nv(); ++i) {
    const int dof = dof_of_[static_cast<std::size_t>(i)];
    d_->qpos[m_->jnt_qposadr[m_->dof_jntid[dof]]] = q[i];
    d_->qvel[dof] = v[i];
  }
  for (std::size_t k = 0; k < held_.joints.size(); ++k) {
    d_->qpos[held_.qpos_of[k]] = held_.q[static_cast<Eigen::Index>(k)];
  }
  // the held joints' actuators at their controls, their activations at rest
  for (std::size_t k = 0; k < held_.actuators.size(); ++k) {
    const int u = held_.actuators[k];
    d_->ctrl[u] = held_.ctrl[static_cast<Eigen::Index>(k)];
    const int first_act = m_->nu - m_->na;
    if (m_->actuator_dyntype[u] != mjDYN_NONE && u >= first_act) d_->act[u - first_act] = d_->ctrl[u];
  }
  mj_forward(m_.get(), d_.get());
  contact_steps_ = 0;
  max_contact_force_ = 0;
}

void Plant::apply(const VecX<double>& tau) {
  // a passive joint gets nothing, whatever τ holds there
  if (actuation_.direct) {
    for (int i = 0; i < nv(); ++i) d_->qfrc_applied[dof_of_[static_cast<std::size_t>(i)]] = tau[i];
    for (int i : actuation_.passive_dofs) d_->qfrc_applied[dof_of_[static_cast<std::size_t>(i)]] = 0;
  } else {
    for (int i = 0; i < nv(); ++i) {
      const int u = actuation_.actuator_of_dof[i];
      if (u >= 0) d_->ctrl[actuator_of_[static_cast<std::size_t>(u)]] = tau[i] * actuation_.ctrl_per_torque[i];
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
  if (!full_q().allFinite() || !Eigen::Map<const VecX<double>>(d_->qvel, m_->nv).allFinite()) {
    if (reason) *reason = "non-finite plant state";
    return false;
  }
  return true;
}

}  // namespace idmpc::mj
