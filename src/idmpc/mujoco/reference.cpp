#include "idmpc/mujoco/reference.hpp"

#include <stdexcept>

namespace idmpc::mj {

Reference::Reference(const mjModel* m) {
  install_error_handlers();
  m_.reset(mj_copyModel(nullptr, m));
  if (!m_) throw std::runtime_error("MuJoCo could not copy the model");
  m_->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_ACTUATION;
  d_ = make_data(m_.get());
}

void Reference::set_state(const VecX<double>& q, const VecX<double>& v) {
  if (q.size() != m_->nq || v.size() != m_->nv) {
    throw std::invalid_argument("state size does not match the model: expected " +
                                std::to_string(m_->nq) + ", got " + std::to_string(q.size()));
  }
  mju_copy(d_->qpos, q.data(), m_->nq);
  mju_copy(d_->qvel, v.data(), m_->nv);
  mju_zero(d_->ctrl, m_->nu);
  mju_zero(d_->qfrc_applied, m_->nv);
  mju_zero(d_->xfrc_applied, 6 * m_->nbody);
}

VecX<double> Reference::inverse(const VecX<double>& q, const VecX<double>& v, const VecX<double>& a) {
  set_state(q, v);
  mju_copy(d_->qacc, a.data(), m_->nv);
  mj_inverse(m_.get(), d_.get());
  return Eigen::Map<const VecX<double>>(d_->qfrc_inverse, m_->nv);
}

VecX<double> Reference::forward(const VecX<double>& q, const VecX<double>& v, const VecX<double>& tau) {
  set_state(q, v);
  mju_copy(d_->qfrc_applied, tau.data(), m_->nv);
  mj_forward(m_.get(), d_.get());
  return Eigen::Map<const VecX<double>>(d_->qacc, m_->nv);
}

MatX<double> Reference::mass_matrix(const VecX<double>& q) {
  set_state(q, VecX<double>::Zero(m_->nv));
  mj_forward(m_.get(), d_.get());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> M(m_->nv, m_->nv);
  mj_fullM(m_.get(), M.data(), d_->qM);
  return M;
}

VecX<double> Reference::solve_mass(const VecX<double>& q, const VecX<double>& x) {
  if (x.size() != m_->nv) throw std::invalid_argument("solve_mass: x must have size nv");
  set_state(q, VecX<double>::Zero(m_->nv));
  mj_forward(m_.get(), d_.get());
  VecX<double> y(m_->nv);
  mj_solveM(m_.get(), d_.get(), y.data(), x.data(), 1);
  return y;
}

}  // namespace idmpc::mj
