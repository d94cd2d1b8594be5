#include "idmpc/solver/shooting.hpp"

#include <algorithm>
#include <cassert>
#include <chrono>

namespace idmpc {

void ShootingDefects::resize(int n, int N) {
  for (MatX<double>* x : {&q, &v, &lmd, &gmm}) *x = MatX<double>::Zero(n, N + 1);
}

double ShootingDefects::squared_norm() const {
  return q.squaredNorm() + v.squaredNorm() + lmd.squaredNorm() + gmm.squaredNorm();
}

void ShootingDefects::assign_scaled(const ShootingDefects& o, double s) {
  q = s * o.q;
  v = s * o.v;
  lmd = s * o.lmd;
  gmm = s * o.gmm;
}

void ShootingTrajectory::resize(int n, int N) {
  for (MatX<double>* x : {&q, &v, &lmd, &gmm}) *x = MatX<double>::Zero(n, N + 1);
}

bool ShootingTrajectory::all_finite() const {
  return q.allFinite() && v.allFinite() && lmd.rightCols(lmd.cols() - 1).allFinite() &&
         gmm.rightCols(gmm.cols() - 1).allFinite();
}

double ShootingTrajectory::max_abs() const {
  const auto tail = [](const MatX<double>& x) { return x.rightCols(x.cols() - 1).cwiseAbs().maxCoeff(); };
  return std::max({tail(q), tail(v), tail(lmd), tail(gmm)});
}

Shooting::Shooting(OcpProblem problem) : problem_(std::move(problem)) {
  const int n = problem_.n(), N = problem_.N();
  x_.resize(n, N);
  a_ = MatX<double>::Zero(n, N);
  u_ = MatX<double>::Zero(n, N);
  d_ = MatX<double>::Zero(problem_.m(), N);
  rho_ = MatX<double>::Zero(problem_.m(), N);
  for (Vec* x : {&hq_, &hv_, &phi_q_, &phi_v_}) *x = Vec::Zero(n);
}

void Shooting::unpack(In U, int stages) {
  const int n = problem_.n(), m = problem_.m(), sd = problem_.stage_dim();
  MatX<double>& input = problem_.formulation() == Formulation::kForwardDynamics ? u_ : a_;
  for (int i = 0; i < stages; ++i) {
    input.col(i) = U.segment(i * sd, n);
    if (m > 0) {
      d_.col(i) = U.segment(i * sd + n, m);
      rho_.col(i) = U.segment(i * sd + n + m, m);
    }
  }
}

void Shooting::residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F, int stages, const ShootingDefects* e) {
  using clock = std::chrono::steady_clock;
  const int sd = problem_.stage_dim();
  assert(stages >= 1 && stages <= N() && U.size() >= stages * sd && F.size() >= stages * sd);
  assert(e == nullptr || stages == N());
  const double dtau = T / stages;
  problem_.set_stage_times(t_, dtau);
  const auto t0 = timing_ ? clock::now() : clock::time_point{};

  // forward sweep: explicit Euler from the measured state (eq. 12), plus the defects; FD's
  // accelerations are the stage dynamics, ID's are the inputs
  const Evaluation ev = problem_.begin_evaluation();
  const bool fd = problem_.formulation() == Formulation::kForwardDynamics;
  unpack(U, stages);
  auto& q = x_.q;
  auto& v = x_.v;
  q.col(0) = q0;
  v.col(0) = v0;
  for (int i = 0; i < stages; ++i) {
    if (fd) problem_.stage_dynamics(ev, i, q.col(i), v.col(i), u_.col(i), a_.col(i));
    q.col(i + 1) = q.col(i) + dtau * v.col(i);
    v.col(i + 1) = v.col(i) + dtau * a_.col(i);
    if (e) {
      q.col(i + 1) += e->q.col(i);
      v.col(i + 1) += e->v.col(i);
    }
  }
  // what runs once the states are known (ID: the stages' dynamics; in lanes if enabled)
  StageTrajectories traj = trajectories(stages, nullptr);
  problem_.stages_at_states(ev, traj);
  const auto t1 = timing_ ? clock::now() : t0;

  // terminal costates (eqs. 16, 18), then the backward sweep (eqs. 22–24); λ_0, γ_0 are
  // never used, so stage 0 gives F_0 only
  auto& lmd = x_.lmd;
  auto& gmm = x_.gmm;
  problem_.terminal_costate(stages, q.col(stages), v.col(stages), lmd.col(stages), gmm.col(stages));
  if (e) {
    lmd.col(stages) += e->lmd.col(stages);
    gmm.col(stages) += e->gmm.col(stages);
  }
  for (int i = stages - 1; i >= 0; --i) {
    const bool state = i > 0;
    problem_.stage_hamiltonian(ev, i, q.col(i), v.col(i), a_.col(i), u_.col(i), d_.col(i), rho_.col(i),
                               lmd.col(i + 1), gmm.col(i + 1), hq_, hv_, F.segment(i * sd, sd), state);
    if (!state) break;
    lmd.col(i) = lmd.col(i + 1) + dtau * hq_;
    gmm.col(i) = gmm.col(i + 1) + dtau * hv_;
    if (e) {
      lmd.col(i) += e->lmd.col(i);
      gmm.col(i) += e->gmm.col(i);
    }
  }
  if (timing_) {
    times_.rollout += std::chrono::duration<double>(t1 - t0).count();
    times_.costate += std::chrono::duration<double>(clock::now() - t1).count();
  }
  ++times_.evaluations;
}

void Shooting::residual_at(In U, const ShootingTrajectory& at, In q0, In v0, double T, Eigen::Ref<Vec> F,
                           ShootingDefects& e) {
  using clock = std::chrono::steady_clock;
  const int sd = problem_.stage_dim(), N = this->N();
  assert(U.size() == dim() && F.size() == dim());
  const double dtau = T / N;
  problem_.set_stage_times(t_, dtau);
  const auto t0 = timing_ ? clock::now() : clock::time_point{};

  // every stage at its stored state: the stages are independent (FD with adjoints: at the stored
  // costates too, so the whole stage runs in lanes)
  const Evaluation ev = problem_.begin_evaluation();
  x_.q = at.q;
  x_.v = at.v;
  x_.q.col(0) = q0;
  x_.v.col(0) = v0;
  x_.lmd = at.lmd;
  x_.gmm = at.gmm;
  unpack(U, N);
  StageTrajectories traj = trajectories(N, &x_.gmm);
  problem_.stages_at_costates(ev, traj);
  const auto& q = x_.q;
  const auto& v = x_.v;
  e.q.col(N).setZero();
  e.v.col(N).setZero();
  for (int i = 0; i < N; ++i) {
    e.q.col(i) = q.col(i + 1) - q.col(i) - dtau * v.col(i);
    e.v.col(i) = v.col(i + 1) - v.col(i) - dtau * a_.col(i);
  }
  const auto t1 = timing_ ? clock::now() : t0;

  // every stage's Hamiltonian at the stored costates of the next stage
  problem_.terminal_costate(N, q.col(N), v.col(N), phi_q_, phi_v_);
  e.lmd.col(N) = x_.lmd.col(N) - phi_q_;
  e.gmm.col(N) = x_.gmm.col(N) - phi_v_;
  e.lmd.col(0).setZero();
  e.gmm.col(0).setZero();
  for (int i = N - 1; i >= 0; --i) {
    const bool state = i > 0;
    problem_.stage_hamiltonian(ev, i, q.col(i), v.col(i), a_.col(i), u_.col(i), d_.col(i), rho_.col(i),
                               x_.lmd.col(i + 1), x_.gmm.col(i + 1), hq_, hv_, F.segment(i * sd, sd), state);
    if (!state) break;
    e.lmd.col(i) = x_.lmd.col(i) - x_.lmd.col(i + 1) - dtau * hq_;
    e.gmm.col(i) = x_.gmm.col(i) - x_.gmm.col(i + 1) - dtau * hv_;
  }
  if (timing_) {
    times_.rollout += std::chrono::duration<double>(t1 - t0).count();
    times_.costate += std::chrono::duration<double>(clock::now() - t1).count();
  }
  ++times_.evaluations;
}

}  // namespace idmpc
