#include "idmpc/solver/cgmres.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/LU>

#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/model/checks.hpp"
#include "idmpc/solver/riccati.hpp"

namespace idmpc {
namespace {

// a solution or residual this large has left any physical meaning: divergence
constexpr double kBlowUp = 1e8;

// full-horizon start (init_full_horizon): the horizon grows from 0 in this many steps, each
// solved by Newton–GMRES from the last; with torque limits the dummy weight starts this many
// times larger (the bounds then act as a strong barrier, the solution stays well inside) and
// comes down a decade per solve. Chosen on the Panda reach: with r_d at its nominal value from
// the start, or the horizon opened in one step, Newton stalls at ‖F‖ ≈ 10–10⁴.
constexpr int kInitHorizonSteps = 10;
constexpr int kInitDummyWeightDecades = 4;
// Krylov dimension of those Newton steps (GMRES from zero, no restart)
constexpr int kInitKrylov = 200;
// fraction of the distance to d = 0, ρ = 0 a Newton step may cover
constexpr double kFractionToBoundary = 0.95;
// Newton steps are halved down to this before a level is given up
constexpr double kMinimumStep = 1e-8;
// a level counts as solved at init_tolerance·√dim, or at this fraction of its initial ‖F‖
constexpr double kInitRelativeTolerance = 1e-8;
// a horizon step that Newton cannot solve is halved, down to this fraction of T/kInitHorizonSteps
constexpr double kInitMinimumHorizonStep = 1.0 / 64;
// the full-horizon start first solves the problem by the Riccati solver (Gauss–Newton SQP with a
// line search on the cost: a globalized method, where Newton on ‖F‖ stalls in a nonconvex
// problem), at most this many iterations to this KKT residual, then polishes its inputs by
// Newton–GMRES on F; the continuation below runs only if ‖F‖ stays above kStartSolved
constexpr int kInitRiccatiIterations = 200;
constexpr double kInitRiccatiTolerance = 1e-9;

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

std::string to_string(ShootingScheme s) { return s == ShootingScheme::kSingle ? "single" : "multiple"; }

ShootingScheme parse_shooting(const std::string& s) {
  if (s == "single") return ShootingScheme::kSingle;
  if (s == "multiple") return ShootingScheme::kMultiple;
  throw std::invalid_argument("shooting must be 'single' or 'multiple', got '" + s + "'");
}

std::string to_string(Products p) { return p == Products::kDifference ? "difference" : "exact"; }

Products parse_products(const std::string& s) {
  if (s == "difference") return Products::kDifference;
  if (s == "exact") return Products::kExact;
  throw std::invalid_argument("products must be 'difference' or 'exact', got '" + s + "'");
}

void CgmresSettings::validate() const {
  require(kmax >= 1, "kmax must be at least 1", kmax);
  require(dt > 0 && std::isfinite(dt), "sampling period dt must be positive", dt);
  require(zeta >= 0 && std::isfinite(zeta), "zeta must be non-negative (0 = 1/dt)", zeta);
  require(h > 0 && std::isfinite(h), "finite-difference increment h must be positive", h);
  require(Tf > 0 && std::isfinite(Tf), "horizon length Tf must be positive", Tf);
  require(alpha >= 0 && std::isfinite(alpha), "horizon growth alpha must be non-negative", alpha);
  require(!init_full_horizon || alpha == 0,
          "init_full_horizon needs alpha = 0 (the horizon starts at Tf; with alpha > 0 it starts at zero length)",
          alpha);
}

Cgmres::Cgmres(Shooting& ocp, const CgmresSettings& settings)
    : ocp_(ocp),
      settings_(validated(settings)),
      horizon_(settings.Tf, settings.alpha),
      gmres_(ocp.dim(), settings.kmax) {
  if (settings_.zeta == 0) settings_.zeta = 1.0 / settings_.dt;
  const int dim = ocp.dim(), n = ocp.n();
  for (VecX<double>* x : {&U_, &Udot_, &F_, &Fx_, &Fw_, &Uw_, &b_}) *x = VecX<double>::Zero(dim);
  for (VecX<double>* x : {&qh_, &vh_, &a0_}) *x = VecX<double>::Zero(n);
  X_.resize(n, ocp.N());
  E_.resize(n, ocp.N());
  Eh_.resize(n, ocp.N());
  if (settings_.products == Products::kExact) ocp_.enable_exact_products();
}

void Cgmres::set_solution(const Eigen::Ref<const VecX<double>>& U) {
  if (U.size() != U_.size()) {
    throw std::invalid_argument("solution has " + std::to_string(U.size()) + " entries, expected " +
                                std::to_string(U_.size()));
  }
  U_ = U;
  Udot_.setZero();
}

void Cgmres::set_trajectory(const ShootingTrajectory& X) {
  const auto n = static_cast<Eigen::Index>(ocp_.n()), cols = static_cast<Eigen::Index>(ocp_.N() + 1);
  for (const MatX<double>* x : {&X.q, &X.v, &X.lmd, &X.gmm}) {
    if (x->rows() != n || x->cols() != cols) {
      throw std::invalid_argument("trajectory must be " + std::to_string(n) + " x " + std::to_string(cols));
    }
  }
  X_ = X;
}

double Cgmres::initialize(double t, const Eigen::Ref<const VecX<double>>& q,
                          const Eigen::Ref<const VecX<double>>& v) {
  IDMPC_CHECK_ARGUMENT(q.size() == ocp_.n() && v.size() == ocp_.n(), "Cgmres::initialize: q and v must have size n");
  const int ni = ocp_.problem().dummy_offset(), m = ocp_.problem().m(), sd = ocp_.stage_dim();
  const int ne = ocp_.problem().equality_dim();
  const double T = horizon_.length(t);
  const bool full = settings_.init_full_horizon && T > 0;
  ocp_.set_time(t);
  // one stage's unknowns (input, d, ρ, ν): the input starts at zero, ρ = 0 leaves it unconstrained
  VecX<double> z = VecX<double>::Zero(sd);
  if (m > 0) {
    z.segment(ni, m) = ocp_.problem().torque_bounds().half_range();
    ocp_.problem().set_dummy_weight_factor(1.0);
  }
  // the full-horizon start grows the horizon from zero
  const double T0 = full ? 0.0 : T;
  // F_0 of the one-stage problem (every stage sees x)
  auto F_of = [&](const VecX<double>& x) {
    VecX<double> out(sd);
    ocp_.residual(x, q, v, T0, out, 1);
    return out;
  };
  // Newton on the first `size` unknowns (the rest fixed), Jacobian by the library's central
  // differences; returns ‖F_0‖ of those equations
  auto newton = [&](int size) {
    VecX<double> x = z.head(size), F0(size);
    auto F_head = [&](const VecX<double>& y) {
      z.head(size) = y;
      return VecX<double>(F_of(z).head(size));
    };
    double norm = 0;
    for (int it = 0; it <= settings_.init_iterations; ++it) {
      if (interrupt_check_) interrupt_check_();
      F0 = F_head(x);
      norm = F0.norm();
      if (!std::isfinite(norm)) throw std::runtime_error("zero-horizon initialization: non-finite residual");
      if (norm <= settings_.init_tolerance || it == settings_.init_iterations) break;
      x -= central_difference_jacobian(F_head, x).partialPivLu().solve(F0);
    }
    z.head(size) = x;
    return norm;
  };
  // the unconstrained input first; with torque limits, then (d, ρ) consistent with its torque;
  // with limits or passive torques, the whole stage solved (the dummy weight raised for the
  // full-horizon start)
  double norm = newton(ni);
  if (m > 0) {
    if (full) ocp_.problem().set_dummy_weight_factor(std::pow(10.0, kInitDummyWeightDecades));
    F_of(z);
    ocp_.problem().torque_bounds().consistent_dummy(ocp_.first_torque(), z.segment(ni, m), z.segment(ni + m, m));
  }
  if (m + ne > 0) norm = newton(sd);
  for (int i = 0; i < ocp_.N(); ++i) U_.segment(i * sd, sd) = z;
  if (full) {
    // the Riccati solver's solution polished; else (or if better) the continuation from zero
    const VecX<double> zero_horizon = U_;
    norm = start_from_riccati(t, q, v, T);
    if (!(norm <= kStartSolved)) {
      const VecX<double> riccati = U_;
      const double riccati_norm = norm;
      U_ = zero_horizon;
      ocp_.problem().set_dummy_weight_factor(m > 0 ? std::pow(10.0, kInitDummyWeightDecades) : 1.0);
      norm = solve_full_horizon(q, v, T);
      if (riccati_norm < norm) {
        U_ = riccati;
        norm = riccati_norm;
        ocp_.problem().set_dummy_weight_factor(1.0);
      }
    }
  }
  Udot_.setZero();
  residual_norm_ = norm;
  if (multiple()) {
    // the stored trajectories start as the rollout of the solution: zero defects
    ocp_.residual(U_, q, v, T, F_);
    X_ = ocp_.trajectory();
    E_.resize(ocp_.n(), ocp_.N());
  }
  return norm;
}

double Cgmres::start_from_riccati(double t, const Eigen::Ref<const VecX<double>>& q,
                                  const Eigen::Ref<const VecX<double>>& v, double T) {
  const int ni = ocp_.problem().dummy_offset(), m = ocp_.problem().m(), sd = ocp_.stage_dim();
  RiccatiSettings rs;
  rs.init_iterations = kInitRiccatiIterations;
  rs.init_tolerance = kInitRiccatiTolerance;
  try {
    RiccatiSolver riccati(ocp_.problem(), T, settings_.dt, rs);
    if (interrupt_check_) riccati.set_interrupt_check(interrupt_check_);
    riccati.initialize(t, q, v);
    // the dummy weight from 10⁴ × nominal down, as in the continuation: the limits' barrier
    // strong first, the solution kept inside while Newton moves it onto C/GMRES's formulation
    ocp_.problem().set_dummy_weight_factor(m > 0 ? std::pow(10.0, kInitDummyWeightDecades) : 1.0);
    for (int i = 0; i < ocp_.N(); ++i) {
      U_.segment(i * sd, ni) = riccati.inputs().col(i);
      U_.segment(i * sd + ni, sd - ni).setZero();  // (d, ρ) below, ν from zero
    }
  } catch (const std::runtime_error&) {
    return std::numeric_limits<double>::infinity();  // its start diverged: the continuation instead
  }
  if (m > 0) {
    VecX<double> F(ocp_.dim());
    ocp_.residual(U_, q, v, T, F);
    for (int i = 0; i < ocp_.N(); ++i) {
      ocp_.problem().torque_bounds().consistent_dummy(ocp_.torques().col(i), U_.segment(i * sd + ni, m),
                                                      U_.segment(i * sd + ni + m, m));
    }
  }
  return solve_full_horizon(q, v, T, false);
}

// horizon continuation 0 → T, then dummy-weight continuation down to nominal; damped
// Newton–GMRES at each level, (d, ρ) kept positive. Without `continuation`: the horizon is T
// from the start (U_ the Riccati solver's solution), the dummy-weight levels as above
double Cgmres::solve_full_horizon(const Eigen::Ref<const VecX<double>>& q,
                                  const Eigen::Ref<const VecX<double>>& v, double T, bool continuation) {
  const int ni = ocp_.problem().dummy_offset(), m = ocp_.problem().m(), sd = ocp_.stage_dim(), dim = ocp_.dim();
  const double h = settings_.h, tolerance = settings_.init_tolerance * std::sqrt(static_cast<double>(dim));
  Gmres gmres(dim, std::min(dim, kInitKrylov));
  VecX<double> F(dim), Fw(dim), Uw(dim), dU(dim);
  double norm = 0;

  // Newton at horizon Tk from U_; true when ‖F‖ reached the tolerance, or (unless `polish`)
  // 1e-8 of its start
  auto newton = [&](double Tk, bool polish = false) {
    double start = 0;
    for (int it = 0; it <= settings_.init_iterations; ++it) {
      if (interrupt_check_) interrupt_check_();
      ocp_.residual(U_, q, v, Tk, F);
      norm = F.norm();
      if (it == 0) start = norm;
      if (!std::isfinite(norm)) return false;
      if (norm <= (polish ? tolerance : std::max(tolerance, kInitRelativeTolerance * start))) return true;
      if (it == settings_.init_iterations) return false;
      // direction by GMRES on forward-difference products
      auto apply = [&](const Eigen::Ref<const VecX<double>>& W, Eigen::Ref<VecX<double>> out) {
        if (settings_.products == Products::kExact) {
          ocp_.residual_and_product(U_, W, q, v, Tk, Fw, out);
          return;
        }
        Uw = U_ + h * W;
        ocp_.residual(Uw, q, v, Tk, Fw);
        out = (Fw - F) / h;
      };
      dU.setZero();
      gmres.solve(apply, -F, dU);
      // fraction to the boundary d, ρ > 0, then backtracking on ‖F‖
      double step = 1;
      for (int i = 0; i < ocp_.N(); ++i) {
        for (int j = i * sd + ni; j < i * sd + ni + 2 * m; ++j) {
          if (dU[j] < 0) step = std::min(step, -kFractionToBoundary * U_[j] / dU[j]);
        }
      }
      bool descent = false;
      for (; step > kMinimumStep && !descent; step *= 0.5) {
        Uw = U_ + step * dU;
        ocp_.residual(Uw, q, v, Tk, Fw);
        descent = Fw.allFinite() && Fw.norm() < (1 - 1e-4 * step) * norm;
      }
      if (!descent) return false;
      U_ = Uw;
    }
    return false;
  };

  // the horizon opened in steps of at most T/kInitHorizonSteps, halved where Newton fails
  const double max_step = T / kInitHorizonSteps, min_step = max_step * kInitMinimumHorizonStep;
  VecX<double> U_solved = U_;
  double T_solved = continuation ? 0 : T, dT = max_step;
  while (T_solved < T && dT >= min_step) {
    const double Tk = std::min(T, T_solved + dT);
    if (newton(Tk)) {
      T_solved = Tk;
      U_solved = U_;
      dT = std::min(2 * dT, max_step);
    } else {
      U_ = U_solved;
      dT *= 0.5;
    }
  }
  if (T_solved < T) newton(T);  // the best Newton can do from the last solved horizon
  // then a decade less of dummy weight at a time; ρ = r_d / 2sd follows
  for (int left = m > 0 ? kInitDummyWeightDecades - 1 : -1; left >= 0; --left) {
    ocp_.problem().set_dummy_weight_factor(std::pow(10.0, left));
    for (int i = 0; i < ocp_.N(); ++i) U_.segment(i * sd + ni + m, m) *= 0.1;
    newton(T);
  }
  // the levels above may stop at 1e-8 of their start; the problem itself is solved to the
  // tolerance, as far as Newton descends (U_ changes only on a descent step)
  newton(T, true);
  ocp_.residual(U_, q, v, T, F);
  norm = F.norm();
  if (!std::isfinite(norm)) throw std::runtime_error("full-horizon initialization: non-finite residual");
  return norm;
}

// (d, ρ) of every stage set consistent with the stage torques of the last evaluation
void Cgmres::synchronize_dummy() {
  const int ni = ocp_.problem().dummy_offset(), m = ocp_.problem().m(), sd = ocp_.stage_dim();
  for (int i = 0; i < ocp_.N(); ++i) {
    ocp_.problem().torque_bounds().consistent_dummy(ocp_.torques().col(i), U_.segment(i * sd + ni, m),
                                                    U_.segment(i * sd + ni + m, m));
    Udot_.segment(i * sd + ni, 2 * m).setZero();
  }
}

void Cgmres::evaluate(const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                      double T) {
  if (multiple()) {
    ocp_.residual_at(U_, X_, q, v, T, F_, E_);
  } else {
    ocp_.residual(U_, q, v, T, F_);
  }
}

bool Cgmres::update(double t, const Eigen::Ref<const VecX<double>>& q,
                    const Eigen::Ref<const VecX<double>>& v) {
  return step(t, q, v, false);
}

bool Cgmres::newton_step(double t, const Eigen::Ref<const VecX<double>>& q,
                         const Eigen::Ref<const VecX<double>>& v) {
  return step(t, q, v, true);
}

bool Cgmres::step(double t, const Eigen::Ref<const VecX<double>>& q, const Eigen::Ref<const VecX<double>>& v,
                  bool frozen) {
  IDMPC_CHECK_ARGUMENT(q.size() == ocp_.n() && v.size() == ocp_.n(), "Cgmres::update: q and v must have size n");
  using clock = std::chrono::steady_clock;
  const auto start = timing_ ? clock::now() : clock::time_point{};
  if (timing_) ocp_.reset_times();
  const long evals0 = ocp_.times().evaluations;
  const double h = settings_.h, T = horizon_.length(t), Th = frozen ? T : horizon_.length(t + h);
  const double zeta = frozen ? 1.0 / settings_.dt : settings_.zeta;
  failure_.clear();
  ocp_.set_time(t);

  // F at the measured state (multiple shooting: with the defects of the stored trajectories),
  // and at the state predicted h ahead with ẋ = (v, a_0); with torque limits, (d, ρ) first made
  // consistent with the torques at the measured state
  evaluate(q, v, T);
  if (ocp_.problem().m() > 0 && !frozen) {
    synchronize_dummy();
    evaluate(q, v, T);
  }
  residual_norm_ = std::sqrt(F_.squaredNorm() + (multiple() ? E_.squared_norm() : 0.0));
  constraint_violation_ = ocp_.problem().m() > 0 ? ocp_.problem().torque_bounds().violation(ocp_.torques()) : 0.0;
  a0_ = ocp_.first_acceleration();
  qh_ = q;
  vh_ = v;
  if (!frozen) {
    qh_ += h * v;
    vh_ += h * a0_;
  }
  // multiple shooting: the defects h ahead, decayed as Ė = −ζE
  const ShootingDefects* defects = nullptr;
  if (multiple()) {
    Eh_.assign_scaled(E_, 1.0 - h * zeta);
    defects = &Eh_;
  }
  // F h ahead in time too: the references' motion is part of ∂F/∂t
  ocp_.set_time(frozen ? t : t + h);
  ocp_.residual(U_, qh_, vh_, Th, Fx_, defects);

  // right-hand side b = −ζF − (∂F/∂x ẋ + ∂F/∂t) by forward difference
  b_ = -zeta * F_ - (Fx_ - F_) / h;
  if (!(b_.allFinite() && std::isfinite(b_.norm()))) {
    // GMRES would return U̇ unchanged and the loop would go on without acting
    failure_ = F_.allFinite() && Fx_.allFinite()
                   ? "the continuation's right-hand side -zeta F - (F(x + h xdot) - F)/h is not finite (zeta = " +
                         text(zeta) + ", h = " + text(h) + ")"
                   : "the optimality residual F became non-finite";
    return false;
  }

  // (∂F/∂U) W at (U, x + hẋ, t + h): exact, or ≈ [F(U + hW, ·) − F(U, ·)] / h; warm start from U̇
  bool vanished = false;
  auto apply = [&](const Eigen::Ref<const VecX<double>>& W, Eigen::Ref<VecX<double>> out) {
    if (settings_.products == Products::kExact) {
      ocp_.residual_and_product(U_, W, qh_, vh_, Th, Fw_, out, defects);
      return;
    }
    Uw_ = U_ + h * W;
    ocp_.residual(Uw_, qh_, vh_, Th, Fw_, defects);
    // h·W below the resolution of U or F: the product is 0 and GMRES would report convergence
    if (Fw_ == Fx_ && !W.isZero(0)) vanished = true;
    out = (Fw_ - Fx_) / h;
  };
  iterations_ = gmres_.solve(apply, b_, Udot_);
  if (vanished) {
    failure_ = "the Frechet products (F(U + hW) - F(U))/h vanish: h = " + text(h) +
               " is below the resolution of U and F (try h = 1e-8)";
    return false;
  }
  if (multiple()) {
    // the stored trajectories move along the condensed direction: (retrieved − stored)/h, the
    // trajectories retrieved at (U + hU̇, x + hẋ, t + h); with exact products, those at
    // (U, x + hẋ, t + h) and their exact tangent along U̇ in place of the difference in U
    const double f = settings_.dt / h;
    const Eigen::Index N = ocp_.N();
    const ShootingTrajectory& r = ocp_.trajectory();
    if (settings_.products == Products::kExact) {
      ocp_.residual_and_product(U_, Udot_, qh_, vh_, Th, Fw_, Uw_, defects);
      const ShootingTrajectory& dr = ocp_.trajectory_tangent();
      X_.q.rightCols(N) += f * (r.q.rightCols(N) - X_.q.rightCols(N)) + settings_.dt * dr.q.rightCols(N);
      X_.v.rightCols(N) += f * (r.v.rightCols(N) - X_.v.rightCols(N)) + settings_.dt * dr.v.rightCols(N);
      X_.lmd.rightCols(N) += f * (r.lmd.rightCols(N) - X_.lmd.rightCols(N)) + settings_.dt * dr.lmd.rightCols(N);
      X_.gmm.rightCols(N) += f * (r.gmm.rightCols(N) - X_.gmm.rightCols(N)) + settings_.dt * dr.gmm.rightCols(N);
    } else {
      Uw_ = U_ + h * Udot_;
      ocp_.residual(Uw_, qh_, vh_, Th, Fw_, defects);
      X_.q.rightCols(N) += f * (r.q.rightCols(N) - X_.q.rightCols(N));
      X_.v.rightCols(N) += f * (r.v.rightCols(N) - X_.v.rightCols(N));
      X_.lmd.rightCols(N) += f * (r.lmd.rightCols(N) - X_.lmd.rightCols(N));
      X_.gmm.rightCols(N) += f * (r.gmm.rightCols(N) - X_.gmm.rightCols(N));
    }
  }
  U_ += settings_.dt * Udot_;
  evaluations_ = static_cast<int>(ocp_.times().evaluations - evals0);

  if (timing_) {
    times_.total = std::chrono::duration<double>(clock::now() - start).count();
    times_.rollout = ocp_.times().rollout;
    times_.costate = ocp_.times().costate;
    times_.gmres = times_.total - times_.rollout - times_.costate;
  }
  if (!(U_.allFinite() && Udot_.allFinite())) {
    failure_ = "the C/GMRES solution became non-finite";
  } else if (multiple() && !X_.all_finite()) {
    failure_ = "the multiple-shooting states or costates became non-finite";
  } else if (!(U_.cwiseAbs().maxCoeff() < kBlowUp)) {
    failure_ = "the C/GMRES solution exceeded 1e8";
  } else if (multiple() && !(X_.max_abs() < kBlowUp)) {
    failure_ = "the multiple-shooting states or costates exceeded 1e8";
  } else if (!(residual_norm_ < kBlowUp)) {
    failure_ = "the optimality residual |F| exceeded 1e8";
  }
  return failure_.empty();
}

}  // namespace idmpc
