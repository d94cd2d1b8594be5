#include "idmpc/solver/cgmres.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/LU>

#include "idmpc/dynamics/finite_difference.hpp"

namespace idmpc {
namespace {

// a solution or residual this large has left any physical meaning: divergence
constexpr double kBlowUp = 1e8;

std::string text(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

void require(bool ok, const std::string& what, double value) {
  if (!ok) throw std::invalid_argument(what + ", got " + text(value));
}

// settings are checked before the GMRES workspace is sized from them
const CgmresSettings& validated(const CgmresSettings& s) {
  s.validate();
  return s;
}

}  // namespace

void CgmresSettings::validate() const {
  require(kmax >= 1, "kmax must be at least 1", kmax);
  require(dt > 0 && std::isfinite(dt), "sampling period dt must be positive", dt);
  require(zeta >= 0 && std::isfinite(zeta), "zeta must be non-negative (0 = 1/dt)", zeta);
  require(h > 0 && std::isfinite(h), "finite-difference increment h must be positive", h);
  require(Tf > 0 && std::isfinite(Tf), "horizon length Tf must be positive", Tf);
  require(alpha >= 0 && std::isfinite(alpha), "horizon growth alpha must be non-negative", alpha);
}

Cgmres::Cgmres(SingleShooting& ocp, const CgmresSettings& settings)
    : ocp_(ocp),
      settings_(validated(settings)),
      horizon_(settings.Tf, settings.alpha),
      gmres_(ocp.dim(), settings.kmax) {
  if (settings_.zeta == 0) settings_.zeta = 1.0 / settings_.dt;
  const int dim = ocp.dim(), n = ocp.n();
  for (VecX<double>* x : {&U_, &Udot_, &F_, &Fx_, &Fw_, &Uw_, &b_}) *x = VecX<double>::Zero(dim);
  for (VecX<double>* x : {&qh_, &vh_, &a0_}) *x = VecX<double>::Zero(n);
}

double Cgmres::initialize(double t, const Eigen::Ref<const VecX<double>>& q,
                          const Eigen::Ref<const VecX<double>>& v) {
  const int n = ocp_.n();
  const double T = horizon_.length(t);
  VecX<double> u = VecX<double>::Zero(n), F0(n);
  // F_0 of the one-stage problem (every stage sees x)
  auto F_of = [&](const VecX<double>& x) {
    VecX<double> out(n);
    ocp_.residual(x, q, v, T, out, 1);
    return out;
  };
  double norm = 0;
  // Newton, Jacobian by the library's central differences
  for (int it = 0; it <= settings_.init_iterations; ++it) {
    F0 = F_of(u);
    norm = F0.norm();
    if (!std::isfinite(norm)) throw std::runtime_error("zero-horizon initialization: non-finite residual");
    if (norm <= settings_.init_tolerance || it == settings_.init_iterations) break;
    u -= central_difference_jacobian(F_of, u).partialPivLu().solve(F0);
  }
  for (int i = 0; i < ocp_.N(); ++i) U_.segment(i * n, n) = u;
  Udot_.setZero();
  residual_norm_ = norm;
  return norm;
}

bool Cgmres::update(double t, const Eigen::Ref<const VecX<double>>& q,
                    const Eigen::Ref<const VecX<double>>& v) {
  using clock = std::chrono::steady_clock;
  const auto start = timing_ ? clock::now() : clock::time_point{};
  if (timing_) ocp_.reset_times();
  const long evals0 = ocp_.times().evaluations;
  const double h = settings_.h, T = horizon_.length(t), Th = horizon_.length(t + h);

  // F at the measured state, and at the state predicted h ahead with ẋ = (v, a_0)
  ocp_.residual(U_, q, v, T, F_);
  residual_norm_ = F_.norm();
  a0_ = ocp_.first_acceleration();
  qh_ = q + h * v;
  vh_ = v + h * a0_;
  ocp_.residual(U_, qh_, vh_, Th, Fx_);

  // right-hand side b = −ζF − (∂F/∂x ẋ + ∂F/∂t) by forward difference
  b_ = -settings_.zeta * F_ - (Fx_ - F_) / h;

  // (∂F/∂U) W ≈ [F(U + hW, x + hẋ, t + h) − F(U, x + hẋ, t + h)] / h, warm start from U̇
  auto apply = [&](const Eigen::Ref<const VecX<double>>& W, Eigen::Ref<VecX<double>> out) {
    Uw_ = U_ + h * W;
    ocp_.residual(Uw_, qh_, vh_, Th, Fw_);
    out = (Fw_ - Fx_) / h;
  };
  iterations_ = gmres_.solve(apply, b_, Udot_);
  U_ += settings_.dt * Udot_;
  evaluations_ = static_cast<int>(ocp_.times().evaluations - evals0);

  if (timing_) {
    times_.total = std::chrono::duration<double>(clock::now() - start).count();
    times_.rollout = ocp_.times().rollout;
    times_.costate = ocp_.times().costate;
    times_.gmres = times_.total - times_.rollout - times_.costate;
  }
  const bool finite = U_.allFinite() && F_.allFinite() && Udot_.allFinite();
  return finite && U_.cwiseAbs().maxCoeff() < kBlowUp && residual_norm_ < kBlowUp;
}

}  // namespace idmpc
