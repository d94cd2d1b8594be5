#include "idmpc/ocp/local_model.hpp"

#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {

StageLocal::StageLocal(int n, int nu)
    : x_next(VecX<double>::Zero(2 * n)),
      A(MatX<double>::Zero(2 * n, 2 * n)),
      B(MatX<double>::Zero(2 * n, nu < 0 ? n : nu)),
      l_x(VecX<double>::Zero(2 * n)),
      l_u(VecX<double>::Zero(nu < 0 ? n : nu)),
      L_xx(MatX<double>::Zero(2 * n, 2 * n)),
      L_uu(MatX<double>::Zero(nu < 0 ? n : nu, nu < 0 ? n : nu)),
      L_ux(MatX<double>::Zero(nu < 0 ? n : nu, 2 * n)),
      tau(VecX<double>::Zero(n)),
      tau_x(MatX<double>::Zero(n, 2 * n)),
      tau_u(MatX<double>::Zero(n, nu < 0 ? n : nu)) {}

LocalModel::LocalModel(const StageTerms& terms, int nu)
    : n_(terms.n()),
      nu_(nu),
      q_(Vec::Zero(n_)),
      v_(Vec::Zero(n_)),
      lq_(Vec::Zero(n_)),
      lv_(Vec::Zero(n_)),
      hvv_(Vec::Zero(n_)),
      g_(Vec::Zero(n_)),
      W_(Vec::Zero(n_)) {}

LocalModel::LocalModel(const LocalModel& o)
    : n_(o.n_), nu_(o.nu_), frame_(o.frame_), q_(o.q_), v_(o.v_), lq_(o.lq_), lv_(o.lv_), hvv_(o.hvv_), g_(o.g_), W_(o.W_) {}

double LocalModel::state_terms(const StageTerms& terms, int i, double scale, In x, Out l_x,
                               Eigen::Ref<MatX<double>> L_xx) {
  const int n = n_;
  const auto q = x.head(n), v = x.tail(n);
  terms.state_gradient(i, q, v, lq_, lv_, frame_);
  l_x.head(n) = scale * lq_;
  l_x.tail(n) = scale * lv_;
  L_xx.setZero();
  terms.state_hessian(i, q, L_xx.topLeftCorner(n, n), hvv_, frame_);
  L_xx.topLeftCorner(n, n) *= scale;
  L_xx.bottomRightCorner(n, n).diagonal() = scale * hvv_;
  // the state part of the stage cost: its torque term vanishes at the torque reference
  return scale * terms.stage_cost(i, q, v, terms.u_ref(i));
}

double LocalModel::torque_cost(const StageTerms& terms, int i, In tau, Out g) {
  g = terms.cost().weights().R.cwiseProduct(tau - terms.u_ref(i));
  return 0.5 * (tau - terms.u_ref(i)).dot(g);
}

void LocalModel::local_model(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out) {
  linearize(terms, i, dtau, x, u, out);
  out.cost += dtau * torque_cost(terms, i, out.tau, g_);
  g_ *= dtau;
  W_ = dtau * terms.cost().weights().R;
  add_torque_terms(W_, g_, out);
}

void LocalModel::terminal(const StageTerms& terms, int stages, In x, TerminalLocal& out) {
  const MatX<double>& P = terms.terminal_weight();
  if (P.size() == 0) {
    out.cost = state_terms(terms, stages, 1.0, x, out.l_x, out.L_xx);
    return;
  }
  // ½eᵀPe (with a frame target's term, if any, in value and gradient): its Hessian is P, the
  // frame term's Gauss–Newton part left out (horizon_setup never sets both)
  const int n = n_;
  terms.state_gradient(stages, x.head(n), x.tail(n), lq_, lv_, frame_);
  out.l_x.head(n) = lq_;
  out.l_x.tail(n) = lv_;
  out.L_xx = P;
  out.cost = terms.terminal_cost(x.head(n), x.tail(n));
}

double LocalModel::terminal_cost(const StageTerms& terms, int /*stages*/, In x) {
  return terms.terminal_cost(x.head(n_), x.tail(n_));
}

// --- forward dynamics -------------------------------------------------------------------------

FdLocalModel::FdLocalModel(const StageTerms& terms)
    : LocalModel(terms, terms.model().n_actuated()),
      data_(terms.model(), DataParts::rnea() | DataParts::aba() | DataParts::rnea_derivatives() |
                               DataParts::minv_matrix() | DataParts::aba_derivatives()),
      torque_(Vec::Zero(terms.n())),
      joints_(terms.model().actuated_joints) {}

void FdLocalModel::scatter(In u, Out tau) const {
  if (nu_ == n_) {
    tau = u;
    return;
  }
  tau.setZero();
  for (int k = 0; k < nu_; ++k) tau[joints_[static_cast<size_t>(k)]] = u[k];
}

void FdLocalModel::linearize(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out) {
  const int n = n_;
  const Model& model = terms.model();
  q_ = x.head(n);
  v_ = x.tail(n);
  scatter(u, out.tau);
  torque_ = out.tau + terms.disturbance();
  aba_derivatives(model, data_, q_, v_, torque_);
  out.x_next.head(n) = q_ + dtau * v_;
  out.x_next.tail(n) = v_ + dtau * data_.qdd;
  out.A.setIdentity();
  out.A.topRightCorner(n, n).diagonal().setConstant(dtau);
  out.A.bottomLeftCorner(n, n) = dtau * data_.da_dq;
  out.A.bottomRightCorner(n, n) += dtau * data_.da_dv;
  out.B.topRows(n).setZero();
  out.tau_u.setZero();
  if (nu_ == n) {
    out.B.bottomRows(n) = dtau * data_.Minv;
    out.tau_u.setIdentity();
  } else {
    for (int k = 0; k < nu_; ++k) {
      const int j = joints_[static_cast<size_t>(k)];
      out.B.bottomRows(n).col(k) = dtau * data_.Minv.col(j);
      out.tau_u(j, k) = 1;
    }
  }
  out.cost = state_terms(terms, i, dtau, x, out.l_x, out.L_xx);
  out.l_u.setZero();
  out.L_uu.setZero();
  out.L_ux.setZero();
  out.tau_x.setZero();
}

void FdLocalModel::add_torque_terms(In W, In g, StageLocal& out) {
  // Sᵀ's rows: the input's joints' weights and gradients
  if (nu_ == n_) {
    out.L_uu.diagonal() += W;
    out.l_u += g;
    return;
  }
  for (int k = 0; k < nu_; ++k) {
    const int j = joints_[static_cast<size_t>(k)];
    out.L_uu(k, k) += W[j];
    out.l_u[k] += g[j];
  }
}

double FdLocalModel::evaluate(const StageTerms& terms, int i, double dtau, In x, In u, Out x_next, Out tau) {
  const int n = n_;
  q_ = x.head(n);
  v_ = x.tail(n);
  scatter(u, tau);
  torque_ = tau + terms.disturbance();
  aba(terms.model(), data_, q_, v_, torque_);
  x_next.head(n) = q_ + dtau * v_;
  x_next.tail(n) = v_ + dtau * data_.qdd;
  return dtau * terms.stage_cost(i, q_, v_, tau);
}

// --- inverse dynamics -------------------------------------------------------------------------

IdLocalModel::IdLocalModel(const StageTerms& terms)
    : LocalModel(terms, terms.n()),
      data_(terms.model(), DataParts::rnea() | DataParts::rnea_derivatives()),
      a_(Vec::Zero(terms.n())),
      Wt_(MatX<double>::Zero(terms.n(), 3 * terms.n())) {}

void IdLocalModel::linearize(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out) {
  const int n = n_;
  q_ = x.head(n);
  v_ = x.tail(n);
  a_ = u;
  rnea_derivatives(terms.model(), data_, q_, v_, a_);
  out.x_next.head(n) = q_ + dtau * v_;
  out.x_next.tail(n) = v_ + dtau * a_;
  out.A.setIdentity();
  out.A.topRightCorner(n, n).diagonal().setConstant(dtau);
  out.B.setZero();
  out.B.bottomRows(n).diagonal().setConstant(dtau);
  out.cost = state_terms(terms, i, dtau, x, out.l_x, out.L_xx);
  const VecX<double>& Qa = terms.cost().weights().Qa;
  out.l_u = dtau * Qa.cwiseProduct(a_);
  out.L_uu.setZero();
  out.L_uu.diagonal() = dtau * Qa;
  out.L_ux.setZero();
  out.cost += 0.5 * dtau * a_.dot(Qa.cwiseProduct(a_));
  out.tau = data_.tau - terms.disturbance();
  out.tau_x.leftCols(n) = data_.dtau_dq;
  out.tau_x.rightCols(n) = data_.dtau_dv;
  out.tau_u = data_.M;
}

void IdLocalModel::add_torque_terms(In W, In g, StageLocal& out) {
  const int n = n_;
  MatX<double>& Wt = Wt_;
  Wt.leftCols(2 * n).noalias() = W.asDiagonal() * out.tau_x;
  Wt.rightCols(n).noalias() = W.asDiagonal() * out.tau_u;
  out.L_xx.noalias() += out.tau_x.transpose() * Wt.leftCols(2 * n);
  out.L_uu.noalias() += out.tau_u.transpose() * Wt.rightCols(n);
  out.L_ux.noalias() += out.tau_u.transpose() * Wt.leftCols(2 * n);
  out.l_x.noalias() += out.tau_x.transpose() * g;
  out.l_u.noalias() += out.tau_u.transpose() * g;
}

double IdLocalModel::evaluate(const StageTerms& terms, int i, double dtau, In x, In u, Out x_next, Out tau) {
  const int n = n_;
  q_ = x.head(n);
  v_ = x.tail(n);
  a_ = u;
  tau = rnea(terms.model(), data_, q_, v_, a_) - terms.disturbance();
  x_next.head(n) = q_ + dtau * v_;
  x_next.tail(n) = v_ + dtau * a_;
  const VecX<double>& Qa = terms.cost().weights().Qa;
  return dtau * (terms.stage_cost(i, q_, v_, tau) + 0.5 * a_.dot(Qa.cwiseProduct(a_)));
}

}  // namespace idmpc
