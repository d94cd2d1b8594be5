#include "idmpc/solver/single_shooting.hpp"

#include <cassert>
#include <chrono>

namespace idmpc {

SingleShooting::SingleShooting(OcpProblem problem) : problem_(std::move(problem)) {
  const int n = problem_.n(), N = problem_.N();
  q_ = MatX<double>::Zero(n, N + 1);
  v_ = MatX<double>::Zero(n, N + 1);
  a_ = MatX<double>::Zero(n, N);
  u_ = MatX<double>::Zero(n, N);
  d_ = MatX<double>::Zero(problem_.m(), N);
  rho_ = MatX<double>::Zero(problem_.m(), N);
  for (Vec* x : {&lmd_, &gmm_, &lmd_next_, &gmm_next_, &hq_, &hv_}) *x = Vec::Zero(n);
}

void SingleShooting::residual(In U, In q0, In v0, double T, Eigen::Ref<Vec> F, int stages) {
  using clock = std::chrono::steady_clock;
  const int n = problem_.n(), m = problem_.m(), sd = problem_.stage_dim();
  assert(stages >= 1 && stages <= N() && U.size() >= stages * sd && F.size() >= stages * sd);
  const double dtau = T / stages;
  const auto t0 = timing_ ? clock::now() : clock::time_point{};

  // forward sweep: explicit Euler from the measured state (eq. 12)
  const bool fd = problem_.formulation() == Formulation::kForwardDynamics;
  const bool lanes = problem_.stages_in_lanes();
  MatX<double>& input = fd ? u_ : a_;
  MatX<double>& output = fd ? a_ : u_;
  q_.col(0) = q0;
  v_.col(0) = v0;
  for (int i = 0; i < stages; ++i) {
    input.col(i) = U.segment(i * sd, n);
    if (m > 0) {
      d_.col(i) = U.segment(i * sd + n, m);
      rho_.col(i) = U.segment(i * sd + n + m, m);
    }
    if (!lanes) problem_.stage_dynamics(i, q_.col(i), v_.col(i), input.col(i), output.col(i));
    q_.col(i + 1) = q_.col(i) + dtau * v_.col(i);
    v_.col(i + 1) = v_.col(i) + dtau * a_.col(i);
  }
  // the ID rollout does not depend on u: the stages' dynamics afterwards, kStageLanes at a time
  if (lanes) {
    for (int i0 = 0; i0 < stages; i0 += kStageLanes) {
      problem_.stage_dynamics_lanes(i0, std::min(kStageLanes, stages - i0), q_, v_, a_, rho_, u_);
    }
  }
  const auto t1 = timing_ ? clock::now() : t0;

  // terminal costates (eqs. 16, 18), then the backward sweep (eqs. 22–24); λ_0, γ_0 are
  // never used, so stage 0 gives F_0 only
  problem_.terminal_costate(q_.col(stages), v_.col(stages), lmd_next_, gmm_next_);
  for (int i = stages - 1; i >= 0; --i) {
    const bool state = i > 0;
    problem_.stage_hamiltonian(i, q_.col(i), v_.col(i), a_.col(i), u_.col(i), d_.col(i), rho_.col(i),
                               lmd_next_, gmm_next_, hq_, hv_, F.segment(i * sd, sd), state);
    if (!state) break;
    lmd_ = lmd_next_ + dtau * hq_;
    gmm_ = gmm_next_ + dtau * hv_;
    lmd_next_.swap(lmd_);
    gmm_next_.swap(gmm_);
  }
  if (timing_) {
    times_.rollout += std::chrono::duration<double>(t1 - t0).count();
    times_.costate += std::chrono::duration<double>(clock::now() - t1).count();
  }
  ++times_.evaluations;
}

}  // namespace idmpc
