#include "idmpc/solver/shooting.hpp"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <stdexcept>
#include <type_traits>

#include "idmpc/model/checks.hpp"

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
  rho_ = MatX<double>::Zero(problem_.m() + problem_.equality_dim(), N);
  for (Vec* x : {&hq_, &hv_, &phi_q_, &phi_v_}) *x = Vec::Zero(n);
  if (problem_.dual_reserved()) enable_exact_products();
}

template <typename S> void Shooting::unpack(Sweep<S>& x, const Eigen::Ref<const VecX<S>>& U, int stages) const {
  const int n = problem_.n(), ni = problem_.input_dim(), m = problem_.m(), ne = problem_.equality_dim();
  const int sd = problem_.stage_dim();
  MatX<S>& input = problem_.formulation() == Formulation::kForwardDynamics ? x.u : x.a;
  const std::vector<int>& joints = problem_.input_joints();
  for (int i = 0; i < stages; ++i) {
    if (ni == n) {
      input.col(i) = U.segment(i * sd, n);
    } else {
      // FD under-actuated: the actuators' torques at their joints, the passive ones zero
      input.col(i).setZero();
      for (int k = 0; k < ni; ++k) input(joints[static_cast<std::size_t>(k)], i) = U[i * sd + k];
    }
    if (m > 0) x.d.col(i) = U.segment(i * sd + ni, m);
    if (m + ne > 0) x.rho.col(i) = U.segment(i * sd + ni + m, m + ne);
  }
}

void Shooting::enable_exact_products() {
  if (exact_products()) return;
  problem_.reserve_dual();
  const int n = problem_.n(), m = problem_.m(), N = problem_.N();
  DualBuffers& b = dual_;
  for (MatX<Dual>* x : {&b.q, &b.v, &b.lmd, &b.gmm}) *x = MatX<Dual>::Zero(n, N + 1);
  for (MatX<Dual>* x : {&b.a, &b.u}) *x = MatX<Dual>::Zero(n, N);
  b.d = MatX<Dual>::Zero(m, N);
  b.rho = MatX<Dual>::Zero(m + problem_.equality_dim(), N);
  for (VecX<Dual>* x : {&b.hq, &b.hv, &b.q0, &b.v0}) *x = VecX<Dual>::Zero(n);
  for (VecX<Dual>* x : {&b.U, &b.F}) *x = VecX<Dual>::Zero(dim());
  dx_.resize(n, N);
}

void Shooting::residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F, int stages, const ShootingDefects* e) {
  sweep<double>({x_.q, x_.v, x_.lmd, x_.gmm, a_, u_, d_, rho_, hq_, hv_}, U, q0, v0, T, F, stages, e);
}

void Shooting::residual_and_product(In U, In W, In q0, In v0, double T, Eigen::Ref<Vec> F, Eigen::Ref<Vec> dF,
                                    const ShootingDefects* e) {
  if (!exact_products()) throw std::logic_error("Shooting::residual_and_product: call enable_exact_products first");
  IDMPC_CHECK_ARGUMENT(U.size() == dim() && W.size() == dim() && F.size() == dim() && dF.size() == dim(),
                       "Shooting::residual_and_product: U, W, F and dF must have size dim");
  DualBuffers& b = dual_;
  for (Eigen::Index k = 0; k < U.size(); ++k) b.U[k] = Dual(U[k], W[k]);
  for (Eigen::Index k = 0; k < q0.size(); ++k) {
    b.q0[k] = Dual(q0[k]);
    b.v0[k] = Dual(v0[k]);
  }
  sweep<Dual>({b.q, b.v, b.lmd, b.gmm, b.a, b.u, b.d, b.rho, b.hq, b.hv}, b.U, b.q0, b.v0, T, b.F, N(), e);
  for (Eigen::Index k = 0; k < F.size(); ++k) {
    F[k] = b.F[k].x;
    dF[k] = b.F[k].dx;
  }
  // the values are the trajectories of the evaluation, the tangents their derivatives along W
  for (Eigen::Index c = 0; c < x_.q.cols(); ++c) {
    for (Eigen::Index r = 0; r < x_.q.rows(); ++r) {
      x_.q(r, c) = b.q(r, c).x;
      x_.v(r, c) = b.v(r, c).x;
      x_.lmd(r, c) = b.lmd(r, c).x;
      x_.gmm(r, c) = b.gmm(r, c).x;
      dx_.q(r, c) = b.q(r, c).dx;
      dx_.v(r, c) = b.v(r, c).dx;
      dx_.lmd(r, c) = b.lmd(r, c).dx;
      dx_.gmm(r, c) = b.gmm(r, c).dx;
      if (c < a_.cols()) {
        a_(r, c) = b.a(r, c).x;
        u_(r, c) = b.u(r, c).x;
      }
    }
  }
}

template <typename S>
void Shooting::sweep(Sweep<S> x, const Eigen::Ref<const VecX<S>>& U, const Eigen::Ref<const VecX<S>>& q0,
                     const Eigen::Ref<const VecX<S>>& v0, double T, Eigen::Ref<VecX<S>> F, int stages,
                     const ShootingDefects* e) {
  using clock = std::chrono::steady_clock;
  constexpr bool dual = std::is_same_v<S, Dual>;
  const int sd = problem_.stage_dim();
  assert(stages >= 1 && stages <= N() && U.size() >= stages * sd && F.size() >= stages * sd);
  assert(e == nullptr || stages == N());
  const double dtau = T / stages;
  problem_.set_stage_times(t_, dtau);
  const auto t0 = timing_ ? clock::now() : clock::time_point{};

  // forward sweep: explicit Euler from the measured state (eq. 12), plus the defects; FD's
  // accelerations are the stage dynamics, ID's are the inputs (in dual numbers every stage's
  // dynamics runs here, stage by stage)
  const Evaluation ev = problem_.begin_evaluation();
  const bool fd = problem_.formulation() == Formulation::kForwardDynamics;
  unpack(x, U, stages);
  x.q.col(0) = q0;
  x.v.col(0) = v0;
  for (int i = 0; i < stages; ++i) {
    if (fd) {
      problem_.stage_dynamics(ev, i, x.q.col(i), x.v.col(i), x.u.col(i), x.a.col(i));
    } else if constexpr (dual) {
      problem_.stage_dynamics(ev, i, x.q.col(i), x.v.col(i), x.a.col(i), x.u.col(i));
    }
    x.q.col(i + 1) = x.q.col(i) + dtau * x.v.col(i);
    x.v.col(i + 1) = x.v.col(i) + dtau * x.a.col(i);
    if (e) {
      x.q.col(i + 1) += e->q.col(i);
      x.v.col(i + 1) += e->v.col(i);
    }
  }
  if constexpr (!dual) {
    // what runs once the states are known (ID: the stages' dynamics; in lanes if enabled)
    StageTrajectories traj = trajectories(stages, nullptr);
    problem_.stages_at_states(ev, traj);
  }
  const auto t1 = timing_ ? clock::now() : t0;

  // terminal costates (eqs. 16, 18), then the backward sweep (eqs. 22–24); λ_0, γ_0 are
  // never used, so stage 0 gives F_0 only
  problem_.terminal_costate(stages, x.q.col(stages), x.v.col(stages), x.lmd.col(stages), x.gmm.col(stages));
  if (e) {
    x.lmd.col(stages) += e->lmd.col(stages);
    x.gmm.col(stages) += e->gmm.col(stages);
  }
  for (int i = stages - 1; i >= 0; --i) {
    const bool state = i > 0;
    problem_.stage_hamiltonian(ev, i, x.q.col(i), x.v.col(i), x.a.col(i), x.u.col(i), x.d.col(i), x.rho.col(i),
                               x.lmd.col(i + 1), x.gmm.col(i + 1), x.hq, x.hv, F.segment(i * sd, sd), state);
    if (!state) break;
    x.lmd.col(i) = x.lmd.col(i + 1) + dtau * x.hq;
    x.gmm.col(i) = x.gmm.col(i + 1) + dtau * x.hv;
    if (e) {
      x.lmd.col(i) += e->lmd.col(i);
      x.gmm.col(i) += e->gmm.col(i);
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
  Sweep<double> x{x_.q, x_.v, x_.lmd, x_.gmm, a_, u_, d_, rho_, hq_, hv_};
  unpack(x, U, N);
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
