#include "idmpc/solver/riccati.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/rnea.hpp"

namespace idmpc {
namespace {

// the trajectory or the KKT residual beyond this: divergence (as C/GMRES's)
constexpr double kBlowUp = 1e8;
// s, z keep this fraction of their distance to zero in a step
constexpr double kFractionToBoundary = 0.995;
// a slack starts at least this fraction of the half range away from zero
constexpr double kMinimumSlack = 1e-2;
// the line search halves the step at most this often, then takes it and raises ε
constexpr int kLineSearchHalvings = 12;
// tries of the backward recursion, ε tenfold each
constexpr int kRegularizationTries = 24;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string text(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

}  // namespace

std::string to_string(SolverKind s) {
  return s == SolverKind::kCgmres ? "cgmres" : s == SolverKind::kRiccati ? "riccati" : "auto";
}

SolverKind parse_solver(const std::string& s) {
  if (s == "cgmres") return SolverKind::kCgmres;
  if (s == "riccati") return SolverKind::kRiccati;
  if (s == "auto") return SolverKind::kAuto;
  throw std::invalid_argument("unknown solver '" + s + "': expected 'cgmres', 'riccati' or 'auto'");
}

void RiccatiSettings::validate() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument("riccati settings: " + what); };
  if (iterations < 1 || iterations > 1000) bad("iterations must be in 1 … 1000, got " + std::to_string(iterations));
  if (init_iterations < 0 || init_iterations > 100000) {
    bad("init_iterations must be in 0 … 100000, got " + std::to_string(init_iterations));
  }
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) bad("tolerance must be >= 0 and finite, got " + text(tolerance));
  if (!(init_tolerance >= 0) || !std::isfinite(init_tolerance)) {
    bad("init_tolerance must be >= 0 and finite, got " + text(init_tolerance));
  }
  if (!(barrier > 0) || !std::isfinite(barrier)) bad("barrier must be positive and finite, got " + text(barrier));
  if (!(regularization > 0) || !(regularization < 1)) {
    bad("regularization must be in (0, 1), got " + text(regularization));
  }
}

RiccatiSolver::RiccatiSolver(OcpProblem problem, double Tf, double dt, const RiccatiSettings& settings)
    : problem_(std::move(problem)), settings_(settings), Tf_(Tf), dt_(dt), hold_(problem_.model(), DataParts::rnea()) {
  settings_.validate();
  if (!(Tf > 0) || !std::isfinite(Tf)) throw std::invalid_argument("horizon length Tf must be positive, got " + text(Tf));
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("sampling period dt must be positive, got " + text(dt));
  const int n = this->n(), N = this->N(), nx = 2 * n;
  const Model& model = problem_.model();
  nu_ = problem_.input_dim();
  ne_ = problem_.equality_dim();
  nw_ = nu_ - ne_;
  eliminate_ = ne_ > 0;
  passive_ = model.unactuated_joints;
  actuated_ = model.actuated_joints;
  model_ = detail::LocalModelHolder(problem_.make_local_model());
  stage_.assign(static_cast<size_t>(N), StageLocal(n, nu_));
  terminal_ = TerminalLocal(n);
  if (eliminate_) {
    reduced_.assign(static_cast<size_t>(N), StageLocal(n, nw_));
    null_.assign(static_cast<size_t>(N), MatX<double>::Zero(n, nw_));
    Yx_.assign(static_cast<size_t>(N), MatX<double>::Zero(n, nx));
    y0_ = MatX<double>::Zero(n, N);
    qp_defect_ = MatX<double>::Zero(nx, N);
    Mee_ = MatX<double>::Zero(ne_, ne_);
    Meu_ = MatX<double>::Zero(ne_, nw_);
    Cx_ = MatX<double>::Zero(ne_, nx);
    LZ_ = MatX<double>::Zero(n, nw_);
    T1_ = MatX<double>::Zero(n, nx);
    c_ = Vec::Zero(ne_);
    nu_e_ = Vec::Zero(ne_);
    llt_e_.assign(static_cast<size_t>(N), Eigen::LLT<MatX<double>>(ne_));
  }
  K0_ = MatX<double>::Zero(nu_, nx);
  const TorqueBounds& b = problem_.torque_bounds();
  const int m = b.m();
  joint_ = b.joints();
  lower_ = b.middle() - b.half_range();
  upper_ = b.middle() + b.half_range();
  mu_ = Vec::Zero(m);
  const VecX<double>& R = problem_.weights().R;
  for (int k = 0; k < m; ++k) {
    const double half = b.half_range()[k];
    mu_[k] = settings_.barrier * dtau() * R[joint_[static_cast<size_t>(k)]] * half * half;
  }
  for (MatX<double>* x : {&X_, &dX_, &Xt_}) *x = MatX<double>::Zero(nx, N + 1);
  T_ = MatX<double>::Zero(n, N);
  for (MatX<double>* x : {&U_, &dU_, &Ut_}) *x = MatX<double>::Zero(nu_, N);
  k_ = MatX<double>::Zero(nw_, N);
  for (MatX<double>* x : {&S_, &Z_, &dS_, &dZ_, &St_}) *x = MatX<double>::Zero(2 * m, N);
  p_ = MatX<double>::Zero(nx, N + 1);
  defect_ = MatX<double>::Zero(nx, N);
  P_.assign(static_cast<size_t>(N + 1), MatX<double>::Zero(nx, nx));
  K_.assign(static_cast<size_t>(N), MatX<double>::Zero(nw_, nx));
  llt_.assign(static_cast<size_t>(N), Eigen::LLT<MatX<double>>(nw_));
  PA_ = MatX<double>::Zero(nx, nx);
  PB_ = MatX<double>::Zero(nx, nw_);
  Qxx_ = MatX<double>::Zero(nx, nx);
  Quu_ = MatX<double>::Zero(nw_, nw_);
  Qux_ = MatX<double>::Zero(nw_, nx);
  for (Vec* x : {&pb_, &qx_, &lmd_, &lmd_next_, &xn_}) *x = Vec::Zero(nx);
  for (Vec* x : {&qu_, &Fi_}) *x = Vec::Zero(nw_);
  gu_ = Vec::Zero(nu_);
  for (Vec* x : {&W_, &g_, &tau_, &u0_, &dtorque_}) *x = Vec::Zero(n);
  regularization_ = settings_.regularization;
}

void RiccatiSolver::set_inputs(const MatX<double>& U) {
  if (U.rows() != nu_ || U.cols() != N() || !U.allFinite()) {
    throw std::invalid_argument("riccati: the inputs must be a finite " + std::to_string(nu_) + " x " +
                                std::to_string(N()) + " matrix");
  }
  U_ = U;
  rolled_out_ = false;
}

void RiccatiSolver::linearize(double t) {
  const int N = this->N(), m = static_cast<int>(joint_.size());
  const double h = dtau();
  problem_.set_stage_times(t, h);
  const StageTerms& terms = problem_.terms();
  const VecX<double>& R = problem_.weights().R;
  for (int i = 0; i < N; ++i) {
    StageLocal& st = stage_[static_cast<size_t>(i)];
    model_->linearize(terms, i, h, X_.col(i), U_.col(i), st);
    T_.col(i) = st.tau;
    // the torque cost and, eliminated, the limits' slacks and multipliers: one weight on τ
    W_ = h * R;
    g_ = h * R.cwiseProduct(st.tau - terms.u_ref(i));
    for (int k = 0; k < m; ++k) {
      const int j = joint_[static_cast<size_t>(k)];
      const double s_up = S_(k, i), z_up = Z_(k, i), s_lo = S_(m + k, i), z_lo = Z_(m + k, i);
      const double r_up = st.tau[j] - upper_[k] + s_up, r_lo = lower_[k] - st.tau[j] + s_lo;
      W_[j] += z_up / s_up + z_lo / s_lo;
      g_[j] += (z_up * r_up + mu_[k]) / s_up - (z_lo * r_lo + mu_[k]) / s_lo - recentering(k, terms.u_ref(i)[j]);
    }
    model_->add_torque_terms(W_, g_, st);
    defect_.col(i) = st.x_next - X_.col(i + 1);
    if (eliminate_) eliminate(i);
  }
  model_->terminal(terms, N, X_.col(N), terminal_);
  evaluations_ += 1;
  // KKT residual: the reduced gradient of the (barrier) objective in the inputs along the
  // costates λ_N = ∇φ, λ_i = ℓ_x + Aᵀλ_{i+1} (divided by Δτ: C/GMRES's F), and the defects;
  // ID under-actuated: the gradient on the constraint's null space (Zᵀ, and Y_xᵀ in λ), the
  // multipliers ν = −M_EE⁻¹(ℓ_u + Bᵀλ)_E and the constraints' residuals c
  double sum = defect_.squaredNorm();
  nu_max_ = 0;
  lmd_ = terminal_.l_x;
  for (int i = N - 1; i >= 0; --i) {
    const StageLocal& st = stage_[static_cast<size_t>(i)];
    gu_ = st.l_u;
    gu_.noalias() += st.B.transpose() * lmd_;
    lmd_next_ = st.l_x;
    lmd_next_.noalias() += st.A.transpose() * lmd_;
    if (eliminate_) {
      Fi_.noalias() = null_[static_cast<size_t>(i)].transpose() * gu_;
      lmd_next_.noalias() += Yx_[static_cast<size_t>(i)].transpose() * gu_;
      for (int k = 0; k < ne_; ++k) {
        const int j = passive_[static_cast<size_t>(k)];
        sum += st.tau[j] * st.tau[j];
        nu_e_[k] = -gu_[j];
      }
      llt_e_[static_cast<size_t>(i)].solveInPlace(nu_e_);  // M_EE factored by eliminate
      nu_max_ = std::max(nu_max_, nu_e_.cwiseAbs().maxCoeff());
    } else {
      Fi_ = gu_;
    }
    sum += Fi_.squaredNorm() / (h * h);
    lmd_.swap(lmd_next_);
  }
  kkt_ = std::sqrt(sum);
}

void RiccatiSolver::eliminate(int i) {
  const StageLocal& st = stage_[static_cast<size_t>(i)];
  StageLocal& r = reduced_[static_cast<size_t>(i)];
  MatX<double>& Z = null_[static_cast<size_t>(i)];
  MatX<double>& Yx = Yx_[static_cast<size_t>(i)];
  auto y0 = y0_.col(i);
  // the passive rows of the torque: c, C_x and τ_u = M split into M_EE, M_EU
  for (int k = 0; k < ne_; ++k) {
    const int j = passive_[static_cast<size_t>(k)];
    c_[k] = st.tau[j];
    Cx_.row(k) = st.tau_x.row(j);
    for (int l = 0; l < ne_; ++l) Mee_(k, l) = st.tau_u(j, passive_[static_cast<size_t>(l)]);
    for (int l = 0; l < nw_; ++l) Meu_(k, l) = st.tau_u(j, actuated_[static_cast<size_t>(l)]);
  }
  Eigen::LLT<MatX<double>>& llt = llt_e_[static_cast<size_t>(i)];
  llt.compute(Mee_);  // a principal block of the mass matrix: positive definite
  llt.solveInPlace(Meu_);
  llt.solveInPlace(Cx_);
  llt.solveInPlace(c_);
  Z.setZero();
  Yx.setZero();
  y0.setZero();
  for (int l = 0; l < nw_; ++l) Z(actuated_[static_cast<size_t>(l)], l) = 1;
  for (int k = 0; k < ne_; ++k) {
    const int j = passive_[static_cast<size_t>(k)];
    Z.row(j) = -Meu_.row(k);
    Yx.row(j) = -Cx_.row(k);
    y0[j] = -c_[k];
  }
  // the stage in (dx, dw): da = Z dw + Y_x dx + y_0
  r.A = st.A;
  r.A.noalias() += st.B * Yx;
  r.B.noalias() = st.B * Z;
  qp_defect_.col(i) = defect_.col(i);
  qp_defect_.col(i).noalias() += st.B * y0;
  LZ_.noalias() = st.L_uu * Z;
  T1_ = st.L_ux;
  T1_.noalias() += st.L_uu * Yx;  // L_ux + L_uu Y_x
  r.L_uu.noalias() = Z.transpose() * LZ_;
  r.L_ux.noalias() = Z.transpose() * T1_;
  r.L_xx = st.L_xx;
  r.L_xx.noalias() += Yx.transpose() * st.L_ux;
  r.L_xx.noalias() += T1_.transpose() * Yx;
  gu_ = st.l_u;
  gu_.noalias() += st.L_uu * y0;
  r.l_u.noalias() = Z.transpose() * gu_;
  r.l_x = st.l_x;
  r.l_x.noalias() += Yx.transpose() * st.l_u;
  r.l_x.noalias() += T1_.transpose() * y0;
}

bool RiccatiSolver::backward(double eps) {
  const int n = this->n(), N = this->N();
  const double h = dtau();
  // ID's constant A, B; with the constraint eliminated its A and B are those of a general stage
  const bool linear = model_->linear_dynamics() && !eliminate_;
  const MatX<double>& defect = eliminate_ ? qp_defect_ : defect_;
  P_[static_cast<size_t>(N)] = terminal_.L_xx;
  p_.col(N) = terminal_.l_x;
  for (int i = N - 1; i >= 0; --i) {
    const StageLocal& st = qp(i);
    const MatX<double>& P = P_[static_cast<size_t>(i + 1)];
    // A = [I, ΔτI; A_q, A_v], B = [0; B_v]: the Euler step's upper rows are the same in every
    // formulation (and after the elimination); ID's lower rows are (0, I) and ΔτI
    const auto Pq = P.leftCols(n), Pv = P.rightCols(n);
    pb_ = p_.col(i + 1);
    pb_.noalias() += P * defect.col(i);
    if (linear) {
      PA_.leftCols(n) = Pq;
      PA_.rightCols(n) = h * Pq + Pv;
      Qxx_.topRows(n) = PA_.topRows(n);
      Qxx_.bottomRows(n) = h * PA_.topRows(n) + PA_.bottomRows(n);
      Quu_ = st.L_uu + (h * h) * P.bottomRightCorner(n, n);
      Qux_ = st.L_ux + h * PA_.bottomRows(n);
      qx_.head(n) = pb_.head(n);
      qx_.tail(n) = h * pb_.head(n) + pb_.tail(n);
      qu_ = st.l_u + h * pb_.tail(n);
    } else {
      const auto Aq = st.A.bottomLeftCorner(n, n), Av = st.A.bottomRightCorner(n, n);
      const auto Bv = st.B.bottomRows(n);
      PA_.leftCols(n) = Pq;
      PA_.leftCols(n).noalias() += Pv * Aq;
      PA_.rightCols(n) = h * Pq;
      PA_.rightCols(n).noalias() += Pv * Av;
      Qxx_.topRows(n) = PA_.topRows(n);
      Qxx_.topRows(n).noalias() += Aq.transpose() * PA_.bottomRows(n);
      Qxx_.bottomRows(n) = h * PA_.topRows(n);
      Qxx_.bottomRows(n).noalias() += Av.transpose() * PA_.bottomRows(n);
      PB_.noalias() = Pv * Bv;
      Quu_ = st.L_uu;
      Quu_.noalias() += Bv.transpose() * PB_.bottomRows(n);
      Qux_ = st.L_ux;
      Qux_.noalias() += Bv.transpose() * PA_.bottomRows(n);
      qx_.head(n) = pb_.head(n);
      qx_.head(n).noalias() += Aq.transpose() * pb_.tail(n);
      qx_.tail(n) = h * pb_.head(n);
      qx_.tail(n).noalias() += Av.transpose() * pb_.tail(n);
      qu_ = st.l_u;
      qu_.noalias() += Bv.transpose() * pb_.tail(n);
    }
    Qxx_ += st.L_xx;
    qx_ += st.l_x;
    const double scale = std::max(1e-300, Quu_.diagonal().cwiseAbs().maxCoeff());
    Quu_.diagonal().array() += eps * scale;
    Eigen::LLT<MatX<double>>& llt = llt_[static_cast<size_t>(i)];
    llt.compute(Quu_);
    if (llt.info() != Eigen::Success) return false;
    // K = −Q_uu⁻¹Q_ux, k = −Q_uu⁻¹q_u, in place (no temporaries: an update allocates nothing)
    MatX<double>& K = K_[static_cast<size_t>(i)];
    K = Qux_;
    llt.solveInPlace(K);
    K *= -1;
    llt.solveInPlace(qu_);
    k_.col(i) = -qu_;
    MatX<double>& Pi = P_[static_cast<size_t>(i)];
    Pi = Qxx_;
    Pi.noalias() += Qux_.transpose() * K;
    // symmetric up to rounding: its lower triangle mirrored
    for (Eigen::Index c = 1; c < Pi.cols(); ++c) {
      for (Eigen::Index r = 0; r < c; ++r) Pi(r, c) = Pi(c, r);
    }
    p_.col(i) = qx_;
    p_.col(i).noalias() += Qux_.transpose() * k_.col(i);
  }
  return true;
}

void RiccatiSolver::forward() {
  const int n = this->n(), N = this->N(), m = static_cast<int>(joint_.size());
  const double h = dtau();
  const bool linear = model_->linear_dynamics();
  const bool input_torque = model_->torque_is_input();
  dX_.col(0).setZero();  // x_0 is the measured state
  for (int i = 0; i < N; ++i) {
    const StageLocal& st = stage_[static_cast<size_t>(i)];
    const auto dq = dX_.col(i).head(n), dv = dX_.col(i).tail(n);
    if (eliminate_) {
      // dw = k + K dx, then da = Z dw + Y_x dx + y_0
      Fi_ = k_.col(i);
      Fi_.noalias() += K_[static_cast<size_t>(i)] * dX_.col(i);
      dU_.col(i) = y0_.col(i);
      dU_.col(i).noalias() += null_[static_cast<size_t>(i)] * Fi_;
      dU_.col(i).noalias() += Yx_[static_cast<size_t>(i)] * dX_.col(i);
    } else {
      dU_.col(i) = k_.col(i);
      dU_.col(i).noalias() += K_[static_cast<size_t>(i)] * dX_.col(i);
    }
    auto next = dX_.col(i + 1);
    next.head(n) = dq + h * dv + defect_.col(i).head(n);
    if (linear) {
      next.tail(n) = dv + h * dU_.col(i) + defect_.col(i).tail(n);
    } else {
      next.tail(n) = defect_.col(i).tail(n);
      next.tail(n).noalias() += st.A.bottomRows(n) * dX_.col(i);
      next.tail(n).noalias() += st.B.bottomRows(n) * dU_.col(i);
    }
    if (m == 0) continue;
    // the torque's change, then the slacks' and multipliers' steps
    if (input_torque && nu_ == n) {
      dtorque_ = dU_.col(i);
    } else {
      dtorque_.noalias() = st.tau_x * dX_.col(i);
      dtorque_.noalias() += st.tau_u * dU_.col(i);
    }
    for (int k = 0; k < m; ++k) {
      const int j = joint_[static_cast<size_t>(k)];
      for (int side = 0; side < 2; ++side) {
        const int r = side * m + k;
        const double sign = side == 0 ? 1.0 : -1.0;  // g = τ − upper, lower − τ
        const double g = side == 0 ? st.tau[j] - upper_[k] : lower_[k] - st.tau[j];
        const double s = S_(r, i), z = Z_(r, i), res = g + s, dg = sign * dtorque_[j];
        dS_(r, i) = -res - dg;
        dZ_(r, i) = z / s * (dg + res) - z + mu_[k] / s;
      }
    }
  }
}

double RiccatiSolver::recentering(int k, double u_ref) const {
  // the barrier's slope at the torque reference; subtracted, the barrier pulls nothing off a
  // target held within the limits (a reference outside them cannot be held anyway)
  if (!(u_ref > lower_[k] && u_ref < upper_[k])) return 0;
  return mu_[k] * (1 / (upper_[k] - u_ref) - 1 / (u_ref - lower_[k]));
}

double RiccatiSolver::max_step(const MatX<double>& s, const MatX<double>& ds) const {
  double alpha = 1;
  for (Eigen::Index j = 0; j < s.cols(); ++j) {
    for (Eigen::Index r = 0; r < s.rows(); ++r) {
      if (ds(r, j) < 0) alpha = std::min(alpha, -kFractionToBoundary * s(r, j) / ds(r, j));
    }
  }
  return alpha;
}

double RiccatiSolver::merit(double alpha, double nu) {
  const int N = this->N(), m = static_cast<int>(joint_.size());
  const double h = dtau();
  const StageTerms& terms = problem_.terms();
  Xt_ = X_ + alpha * dX_;
  Ut_ = U_ + alpha * dU_;
  St_ = S_ + alpha * dS_;
  double total = 0;
  for (int i = 0; i < N; ++i) {
    total += model_->evaluate(terms, i, h, Xt_.col(i), Ut_.col(i), xn_, tau_);
    total += nu * (xn_ - Xt_.col(i + 1)).lpNorm<1>();
    if (eliminate_) {
      for (int j : passive_) total += nu * std::abs(tau_[j]);  // ID's passive torques: constraints
    }
    for (int k = 0; k < m; ++k) {
      const int j = joint_[static_cast<size_t>(k)];
      const double s_up = St_(k, i), s_lo = St_(m + k, i);
      total += nu * (std::abs(tau_[j] - upper_[k] + s_up) + std::abs(lower_[k] - tau_[j] + s_lo));
      total -= mu_[k] * (std::log(s_up) + std::log(s_lo)) + recentering(k, terms.u_ref(i)[j]) * tau_[j];
    }
  }
  evaluations_ += 1;
  return total + model_->terminal_cost(terms, N, Xt_.col(N));
}

void RiccatiSolver::take_step(double alpha, double alpha_dual) {
  X_ += alpha * dX_;
  U_ += alpha * dU_;
  S_ += alpha * dS_;
  Z_ += alpha_dual * dZ_;
}

double RiccatiSolver::iterate(double t, In q, In v, bool search) {
  const int n = this->n();
  const auto t0 = timing_ ? Clock::now() : Clock::time_point();
  X_.col(0).head(n) = q;
  X_.col(0).tail(n) = v;
  if (!rolled_out_) rollout_and_slacks(t);
  linearize(t);
  const double kkt = kkt_;
  const auto t1 = timing_ ? Clock::now() : Clock::time_point();
  double eps = regularization_;
  int tries = 0;
  while (!backward(eps)) {
    if (++tries == kRegularizationTries) break;
    eps *= 10;
  }
  forward();
  const auto t2 = timing_ ? Clock::now() : Clock::time_point();
  const double alpha_max = max_step(S_, dS_), alpha_dual = max_step(Z_, dZ_);
  double alpha = alpha_max;
  if (search) {
    const double nu = 1 + std::max({p_.cwiseAbs().maxCoeff(), Z_.size() ? Z_.maxCoeff() : 0.0, nu_max_});
    const double m0 = merit(0, nu);
    int halvings = 0;
    while (!(merit(alpha, nu) < m0) && halvings < kLineSearchHalvings) {
      alpha *= 0.5;
      ++halvings;
    }
    // no decrease: a small step, and more regularization for the next iteration
    if (halvings == kLineSearchHalvings) eps *= 10;
  }
  take_step(alpha, alpha_dual);
  regularization_ = std::max(settings_.regularization, eps / 10);
  set_first_input();
  if (eliminate_) {
    K0_ = Yx_.front();
    K0_.noalias() += null_.front() * K_.front();
  } else {
    K0_ = K_.front();
  }
  ++iterations_;
  if (timing_) {
    times_.rollout += std::chrono::duration<double>(t1 - t0).count();
    times_.costate += std::chrono::duration<double>(t2 - t1).count();
    times_.gmres += seconds_since(t2);
  }
  return kkt;
}

void RiccatiSolver::rollout_and_slacks(double t) {
  const int N = this->N(), m = static_cast<int>(joint_.size());
  const double h = dtau();
  problem_.set_stage_times(t, h);
  const StageTerms& terms = problem_.terms();
  for (int i = 0; i < N; ++i) {
    model_->evaluate(terms, i, h, X_.col(i), U_.col(i), xn_, tau_);
    X_.col(i + 1) = xn_;
    T_.col(i) = tau_;
    for (int k = 0; k < m; ++k) {
      const int j = joint_[static_cast<size_t>(k)];
      const double floor = kMinimumSlack * 0.5 * (upper_[k] - lower_[k]);
      S_(k, i) = std::max(upper_[k] - tau_[j], floor);
      S_(m + k, i) = std::max(tau_[j] - lower_[k], floor);
      Z_(k, i) = mu_[k] / S_(k, i);
      Z_(m + k, i) = mu_[k] / S_(m + k, i);
    }
  }
  rolled_out_ = true;
}

double RiccatiSolver::initialize(double t, In q, In v) {
  const int n = this->n();
  failure_.clear();
  times_ = {};
  evaluations_ = 0;
  iterations_ = 0;
  regularization_ = settings_.regularization;
  // the start: every stage holds the measured state (FD: the torque that holds q at rest; ID:
  // zero acceleration), the trajectory rolled out from there
  if (problem_.formulation() == Formulation::kForwardDynamics) {
    // (under-actuated: the actuated joints' share of it)
    const Vec zero = Vec::Zero(n);
    const Vec hold = rnea(problem_.model(), hold_, Vec(q), zero, zero) - problem_.disturbance();
    for (int k = 0; k < nu_; ++k) U_.row(k).setConstant(hold[nu_ == n ? k : actuated_[static_cast<size_t>(k)]]);
  } else {
    U_.setZero();
  }
  X_.col(0).head(n) = q;
  X_.col(0).tail(n) = v;
  rolled_out_ = false;
  const auto t0 = Clock::now();
  for (int it = 0; it < settings_.init_iterations; ++it) {
    if (interrupt_check_) interrupt_check_();
    const double kkt = iterate(t, q, v, true);
    if (!check_finite(false)) throw std::runtime_error("riccati start: " + failure_);
    if (kkt < settings_.init_tolerance) break;
  }
  if (!rolled_out_) rollout_and_slacks(t);  // (no iteration: the guess's rollout)
  linearize(t);  // the residual where the start ended
  if (!check_finite(false)) throw std::runtime_error("riccati start: " + failure_);
  set_first_input();
  violation_ = violation();
  times_.total = seconds_since(t0);
  return kkt_;
}

bool RiccatiSolver::update(double t, In q, In v) {
  IDMPC_CHECK_ARGUMENT(q.size() == n() && v.size() == n(), "RiccatiSolver::update: q and v must have size n");
  const auto t0 = Clock::now();
  failure_.clear();
  times_ = {};
  evaluations_ = 0;
  iterations_ = 0;
  // the warm start: the previous solution moved Δt along its stages
  const double delta = std::min(1.0, dt_ / dtau());
  const int N = this->N();
  for (int i = 0; i + 1 < N; ++i) {
    U_.col(i) += delta * (U_.col(i + 1) - U_.col(i));
    S_.col(i) += delta * (S_.col(i + 1) - S_.col(i));
    Z_.col(i) += delta * (Z_.col(i + 1) - Z_.col(i));
  }
  for (int i = 1; i < N; ++i) X_.col(i) += delta * (X_.col(i + 1) - X_.col(i));
  for (int it = 0; it < settings_.iterations; ++it) {
    const double kkt = iterate(t, q, v, settings_.line_search);
    if (it == 0) {
      violation_ = violation();
      kkt_first_ = kkt;
    }
    if (!check_finite()) return false;
    if (settings_.tolerance > 0 && kkt < settings_.tolerance) break;
  }
  kkt_ = kkt_first_;
  times_.total = seconds_since(t0);
  return true;
}

void RiccatiSolver::set_first_input() {
  if (nu_ == n()) {
    u0_ = U_.col(0);
    return;
  }
  u0_.setZero();
  for (int k = 0; k < nu_; ++k) u0_[actuated_[static_cast<size_t>(k)]] = U_(k, 0);
}

double RiccatiSolver::violation() const {
  double worst = 0;
  for (int i = 0; i < N(); ++i) {
    for (size_t k = 0; k < joint_.size(); ++k) {
      const double tau = T_(joint_[k], i);
      worst = std::max({worst, tau - upper_[static_cast<Eigen::Index>(k)], lower_[static_cast<Eigen::Index>(k)] - tau});
    }
  }
  return worst;
}

bool RiccatiSolver::check_finite(bool bound_residual) {
  if (!X_.allFinite() || !U_.allFinite() || !S_.allFinite() || !Z_.allFinite() || !std::isfinite(kkt_)) {
    failure_ = "the Riccati solution became non-finite";
  } else if (!(X_.cwiseAbs().maxCoeff() < kBlowUp) || !(U_.cwiseAbs().maxCoeff() < kBlowUp)) {
    failure_ = "the Riccati solution exceeded 1e8";
  } else if (bound_residual && !(kkt_ < kBlowUp)) {
    failure_ = "the KKT residual exceeded 1e8";
  } else {
    return true;
  }
  return false;
}

}  // namespace idmpc
