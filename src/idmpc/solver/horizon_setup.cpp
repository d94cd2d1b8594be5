#include "idmpc/solver/horizon_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {
namespace {

// the "auto" weights (horizon_setup.hpp)
constexpr double kAutoQq = 100, kAutoQv = 10, kAutoTorqueCost = 10;
// with a frame target the joint terms only hold the posture and damp: a hundredth and a tenth
constexpr double kAutoPostureQq = 1, kAutoPostureQv = 1;
// without a declared limit: the holding torque twice over plus this acceleration of the
// joint's own inertia [rad/s²]
constexpr double kAutoAcceleration = 20;
// the fastest closed-loop motion the horizon step Δτ resolves: ω·Δτ ≤ this
constexpr double kAutoStepFraction = 0.35;
// an under-actuated start farther than this from its target [rad or m, any joint] is a
// swing-up, outside the reach of the target's linearization (sin θ ≈ θ within 10 %)
constexpr double kLqrReach = 0.7853981633974483;

std::string text(double x) {
  std::ostringstream o;
  o.precision(3);
  o << x;
  return o.str();
}

std::string list(const VecX<double>& x) {
  std::string s;
  for (Eigen::Index i = 0; i < x.size(); ++i) s += (i ? " " : "") + text(x[i]);
  return s;
}

// max eig(M(q)⁻¹D) over the given configurations: of the symmetric D^½ M⁻¹ D^½
double damping_rate(const Model& model, const std::vector<VecX<double>>& qs) {
  if ((model.damping.array() == 0).all()) return 0;
  Data data(model);
  const VecX<double> sqrt_d = model.damping.cwiseSqrt();
  double rate = 0;
  for (const VecX<double>& q : qs) {
    const MatX<double> Minv = crba(model, data, q).inverse();
    const MatX<double> S = sqrt_d.asDiagonal() * Minv * sqrt_d.asDiagonal();
    rate = std::max(rate, Eigen::SelfAdjointEigenSolver<MatX<double>>(S, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff());
  }
  return rate;
}

// the largest real part of the eigenvalues of the dynamics linearized at rest with the torques
// held, [[0, I], [−M⁻¹∂τ/∂q, −M⁻¹∂τ/∂v]], over the configurations; 0 if none is positive
double open_loop_rate(const Model& model, const std::vector<VecX<double>>& qs) {
  const int n = model.n;
  Data data(model, DataParts::rnea() | DataParts::rnea_derivatives());
  const VecX<double> zero = VecX<double>::Zero(n);
  MatX<double> A = MatX<double>::Zero(2 * n, 2 * n);
  A.topRightCorner(n, n).setIdentity();
  double rate = 0;
  for (const VecX<double>& q : qs) {
    rnea_derivatives(model, data, q, zero, zero);
    const auto M = data.M.ldlt();
    A.bottomLeftCorner(n, n) = -M.solve(data.dtau_dq);
    A.bottomRightCorner(n, n) = -M.solve(data.dtau_dv);
    rate = std::max(rate, Eigen::EigenSolver<MatX<double>>(A, false).eigenvalues().real().maxCoeff());
  }
  return rate;
}

// max over the configurations of (M(q)⁻¹)_jj: joint j's own acceleration per unit torque
VecX<double> inverse_inertia_diagonal(const Model& model, const std::vector<VecX<double>>& qs) {
  Data data(model);
  VecX<double> out = VecX<double>::Zero(model.n);
  for (const VecX<double>& q : qs) out = out.cwiseMax(MatX<double>(crba(model, data, q).inverse()).diagonal());
  return out;
}

// "auto" R: the torque-range scale 10/τ_j², raised where the regulator it makes would be faster
// than the horizon step resolves. For joint j alone (effective inertia m_j = 1/(M⁻¹)_jj at its
// lightest over q0 and q_ref) the LQR of ½Q_q e² + ½R u² has stiffness √(Q_q/R) and frequency
// ω = (Q_q/R)^¼/√m_j; ω·Δτ ≤ 0.35 needs R ≥ Q_q/(m_j² ω_max⁴), ω_max = 0.35/Δτ.
OcpWeights auto_weights(const ControllerSettings& s, const std::vector<VecX<double>>& configurations,
                        const Model& model, const Model& stepped, double dtau, const VecX<double>& lower,
                        const VecX<double>& upper, std::vector<std::string>& notes) {
  OcpWeights w = s.weights;
  const int n = model.n;
  const bool frame_target = s.frame_target.has_value();
  if (w.Qq.size() == 0) w.Qq = VecX<double>::Constant(n, frame_target ? kAutoPostureQq : kAutoQq);
  if (w.Qv.size() == 0) w.Qv = VecX<double>::Constant(n, frame_target ? kAutoPostureQv : kAutoQv);
  if (w.R.size() == 0) {
    Data data(model);
    const VecX<double> zero = VecX<double>::Zero(n);
    const VecX<double> hold = rnea(model, data, s.q_ref, zero, zero);
    const VecX<double> inertia = crba(model, data, s.q_ref).diagonal();
    VecX<double> scale(n);
    for (int j = 0; j < n; ++j) {
      const bool lo = std::isfinite(lower[j]), hi = std::isfinite(upper[j]);
      if (lo && hi) {
        scale[j] = 0.5 * (upper[j] - lower[j]);
      } else if (lo || hi) {
        scale[j] = lo ? std::abs(lower[j]) : std::abs(upper[j]);
      } else {
        scale[j] = 2 * std::abs(hold[j]) + kAutoAcceleration * inertia[j];
      }
      scale[j] = std::max(scale[j], 1e-6);
    }
    w.R = kAutoTorqueCost * scale.cwiseAbs2().cwiseInverse();
    const VecX<double> inv_inertia = inverse_inertia_diagonal(stepped, configurations);
    const double omega = kAutoStepFraction / dtau;
    for (int j = 0; j < n; ++j) {
      w.R[j] = std::max(w.R[j], w.Qq[j] * inv_inertia[j] * inv_inertia[j] / std::pow(omega, 4));
    }
    notes.push_back("weights \"auto\": Qq " + text(w.Qq.maxCoeff()) + ", Qv " + text(w.Qv.maxCoeff()) +
                    ", R = max(10/tau_max^2, Qq/(m^2 omega^4)) = [" + list(w.R) + "] (omega = " + text(omega) +
                    " rad/s, well inside what the horizon step resolves)");
  }
  return w;
}

}  // namespace

std::string to_string(ImplicitDamping d) {
  switch (d) {
    case ImplicitDamping::kOff: return "off";
    case ImplicitDamping::kOn: return "on";
    case ImplicitDamping::kAuto: return "auto";
  }
  return "?";
}

ImplicitDamping parse_implicit_damping(const std::string& s) {
  if (s == "off") return ImplicitDamping::kOff;
  if (s == "on") return ImplicitDamping::kOn;
  if (s == "auto") return ImplicitDamping::kAuto;
  throw std::invalid_argument("implicit damping: expected \"off\", \"on\" or \"auto\", got \"" + s + "\"");
}

MatX<double> solve_dare(const MatX<double>& A, const MatX<double>& B, const MatX<double>& Q, const MatX<double>& R) {
  const Eigen::Index nx = A.rows();
  MatX<double> Ak = A, G = B * R.llt().solve(B.transpose()), H = Q;
  const MatX<double> I = MatX<double>::Identity(nx, nx);
  for (int it = 0; it < 100; ++it) {
    const Eigen::PartialPivLU<MatX<double>> W(I + G * H);
    const MatX<double> WA = W.solve(Ak);
    const MatX<double> H1 = H + Ak.transpose() * H * WA;
    G += Ak * W.solve(G * Ak.transpose());
    Ak = Ak * WA;
    const double change = (H1 - H).norm();
    H = 0.5 * (H1 + H1.transpose());
    if (!H.allFinite()) return {};
    if (change <= 1e-12 * H.norm()) {
      // stabilizing: the closed loop A − B K has its eigenvalues inside the unit circle
      const MatX<double> K = (R + B.transpose() * H * B).ldlt().solve(B.transpose() * H * A);
      const Eigen::EigenSolver<MatX<double>> eig(A - B * K, false);
      if (!(eig.eigenvalues().cwiseAbs().maxCoeff() < 1)) return {};
      return H;
    }
  }
  return {};
}

namespace {

// the LQR value of the fixed joint target of an under-actuated model (horizon_setup.hpp), or
// empty with a note saying why not
MatX<double> terminal_lqr(const Model& model, const ControllerSettings& s, SolverKind solver, const OcpWeights& w,
                          double dtau, std::vector<std::string>& notes) {
  const int n = model.n, nu = model.n_actuated();
  if (!model.under_actuated()) return {};
  if (s.frame_target) {
    notes.push_back("under-actuated with a frame target: the terminal cost keeps its diagonal weights");
    return {};
  }
  if (solver == SolverKind::kCgmres && s.cgmres.alpha != 0) {
    // a growing horizon: its step is not the one P is for, and a swing-up starts far from the
    // target, where the target's LQR value means nothing
    notes.push_back("under-actuated with a growing horizon (alpha > 0): the terminal cost keeps its diagonal weights");
    return {};
  }
  if (s.q_start.size() == n && (s.q_start - s.q_ref).cwiseAbs().maxCoeff() > kLqrReach) {
    // a swing-up: the target's linearization means nothing at the start, and its value would
    // rank the states of the swing wrongly
    notes.push_back("under-actuated, starting " + text((s.q_start - s.q_ref).cwiseAbs().maxCoeff()) +
                    " rad from the target (beyond the linearization's reach pi/4): the terminal cost keeps its diagonal weights");
    return {};
  }
  Data data(model);
  const VecX<double> zero = VecX<double>::Zero(n);
  const VecX<double> tau = rnea(model, data, s.q_ref, zero, zero);
  for (int j : model.unactuated_joints) {
    if (std::abs(tau[j]) > 1e-9 * (1 + tau.cwiseAbs().maxCoeff())) {
      notes.push_back("the target needs " + text(tau[j]) + " on passive joint '" +
                      model.joint_names[static_cast<size_t>(j)] +
                      "' (not an equilibrium): the terminal cost keeps its diagonal weights");
      return {};
    }
  }
  aba(model, data, s.q_ref, zero, tau);
  aba_derivatives_after_aba(model, data, s.q_ref, zero);
  MatX<double> A = MatX<double>::Identity(2 * n, 2 * n), B = MatX<double>::Zero(2 * n, nu);
  A.topRightCorner(n, n) = dtau * MatX<double>::Identity(n, n);
  A.bottomLeftCorner(n, n) += dtau * data.da_dq;
  A.bottomRightCorner(n, n) += dtau * data.da_dv;
  MatX<double> R = MatX<double>::Zero(nu, nu);
  for (int k = 0; k < nu; ++k) {
    const int j = model.actuated_joints[static_cast<size_t>(k)];
    B.bottomRows(n).col(k) = dtau * data.Minv.col(j);
    R(k, k) = dtau * w.R[j];
  }
  VecX<double> q(2 * n);
  q << w.Qq, w.Qv;
  const MatX<double> P = solve_dare(A, B, MatX<double>(dtau * q.asDiagonal()), R);
  if (P.size() == 0) {
    notes.push_back("under-actuated: the target's Riccati equation has no stabilizing solution (not stabilizable "
                    "at this step?): the terminal cost keeps its diagonal weights");
    return {};
  }
  notes.push_back("under-actuated: terminal cost = the LQR value of the target (Riccati equation of the horizon step " +
                  text(dtau) + " s at q_ref; largest eigenvalue " + text(P.selfadjointView<Eigen::Lower>().eigenvalues().maxCoeff()) +
                  ")");
  return P;
}

}  // namespace

HorizonSetup setup_horizon(const Model& model, const ControllerSettings& s) {
  const int n = model.n;
  auto check_size = [n](const VecX<double>& x, const char* name, bool may_be_empty) {
    if (x.size() == n || (may_be_empty && x.size() == 0)) return;
    throw std::invalid_argument(std::string("controller settings: ") + name + " has " + std::to_string(x.size()) +
                                " entries, the model " + std::to_string(n) + " joints");
  };
  check_size(s.q_ref, "q_ref", false);
  check_size(s.q_start, "q_start", true);
  check_size(s.torque_lower, "torque_lower", true);
  check_size(s.torque_upper, "torque_upper", true);
  check_size(s.friction_loss, "friction_loss", true);
  check_size(s.friction_velocity, "friction_velocity", true);
  check_size(s.weights.Qq, "weights.Qq", true);
  check_size(s.weights.Qv, "weights.Qv", true);
  check_size(s.weights.Qa, "weights.Qa", true);
  check_size(s.weights.R, "weights.R", true);
  if (s.torque_lower.size() != s.torque_upper.size()) {
    throw std::invalid_argument("controller settings: torque_lower and torque_upper must both be given or both empty");
  }
  for (const VecX<double>* x : {&s.friction_loss, &s.friction_velocity}) {
    if (!x->allFinite() || (x->array() < 0).any()) {
      throw std::invalid_argument(std::string("controller settings: ") +
                                  (x == &s.friction_loss ? "friction_loss" : "friction_velocity") +
                                  " must be finite and non-negative");
    }
  }
  if (s.friction_velocity.size() == n && ((s.friction_loss.array() > 0) && (s.friction_velocity.array() == 0)).any()) {
    throw std::invalid_argument("controller settings: friction_velocity must be positive where there is friction loss");
  }
  std::vector<std::string> notes;
  const double dtau = s.cgmres.Tf / s.N;
  std::vector<VecX<double>> configurations = {s.q_ref};
  if (s.q_start.size() == n) configurations.insert(configurations.begin(), s.q_start);
  const VecX<double> infinite = VecX<double>::Constant(n, std::numeric_limits<double>::infinity());
  const VecX<double> lower = s.torque_lower.size() == n ? s.torque_lower : VecX<double>(-infinite);
  const VecX<double> upper = s.torque_upper.size() == n ? s.torque_upper : infinite;
  const VecX<double> friction_loss = s.friction_loss.size() == n ? s.friction_loss : VecX<double>::Zero(n);

  // friction loss: f·tanh(v/ε), ε given or the smallest with a stable explicit step
  VecX<double> eps = VecX<double>::Zero(n);
  if ((friction_loss.array() > 0).any()) {
    if (s.friction_velocity.size() == n) {
      eps = s.friction_velocity;
    } else {
      // explicit in the friction, implicit or not in the damping, the step's velocity factor is
      // (m − Δτ·f/ε)/(m + Δτ·d) near v = 0, m = 1/(M⁻¹)_jj without the implicit term: ≥ 0 for this ε
      const VecX<double> inv_inertia = inverse_inertia_diagonal(model, configurations);
      for (int j = 0; j < n; ++j) eps[j] = std::max(kMinFrictionVelocity, dtau * friction_loss[j] * inv_inertia[j]);
    }
    for (int j = 0; j < n; ++j) {
      if (!(friction_loss[j] > 0)) eps[j] = 0;
    }
    notes.push_back("joint friction loss in the horizon as f*tanh(v/eps), eps = [" + list(eps) + "] " +
                    (s.friction_velocity.size() == n ? "(given)" : "(\"auto\": the smallest with a stable explicit step)"));
  }
  // (without friction loss given, the model keeps its own friction terms, if any)
  const Model with_friction = s.friction_loss.size() == n ? with_joint_friction(model, friction_loss, eps) : model;
  // the open loop of the horizon's dynamics (its damping as the plant has it, not the step's)
  const double lambda = open_loop_rate(with_friction, configurations);
  const bool ill_conditioned = lambda * s.cgmres.Tf > kIllConditionedGrowth;
  SolverKind solver = s.solver;
  if (solver == SolverKind::kAuto) {
    solver = model.under_actuated() ? SolverKind::kCgmres : SolverKind::kRiccati;
    notes.push_back(solver == SolverKind::kRiccati
                        ? "solver \"auto\": Riccati in both formulations (a fully actuated model; --solver cgmres "
                          "for the paper's C/GMRES)"
                        : "solver \"auto\": C/GMRES in both formulations (an under-actuated model)");
  }
  if (s.formulation == Formulation::kForwardDynamics && solver == SolverKind::kCgmres && ill_conditioned) {
    notes.push_back("the open loop diverges at " + text(lambda) + " 1/s (x" + text(std::exp(lambda * s.cgmres.Tf)) +
                    " over Tf): FD's single-shooting rollout is ill-conditioned for C/GMRES here; ID's or the Riccati "
                    "solver's is not");
  }

  // damping: explicit unless asked for, or unstable with "auto"; implicit needs a fixed horizon
  const double ratio = dtau * damping_rate(model, configurations);
  const bool fixed_horizon = solver == SolverKind::kRiccati || s.cgmres.alpha == 0;
  bool implicit = s.implicit_damping == ImplicitDamping::kOn;
  if (implicit && !fixed_horizon) {
    throw std::invalid_argument("controller settings: implicit damping needs a fixed horizon (cgmres.alpha = 0): "
                                "its step T_f/N is built into the horizon model");
  }
  if (s.implicit_damping == ImplicitDamping::kAuto && ratio > 1) {
    if (fixed_horizon) {
      implicit = true;
      notes.push_back("joint damping integrated implicitly in the horizon (implicit_damping \"auto\"): "
                      "dtau*max eig(M^-1 D) = " + text(ratio) + " > 1, the explicit Euler step would be unstable");
    } else {
      notes.push_back("joint damping makes the explicit horizon step unstable (dtau*max eig(M^-1 D) = " + text(ratio) +
                      " > 1 at the longest step) and implicit damping needs a fixed horizon: use --alpha 0");
    }
  }
  const double implicit_step = implicit ? dtau : 0.0;
  // the inertia the horizon step sees: with implicit damping M + Δτ·D
  const Model stepped = with_implicit_damping(model, implicit_step);

  auto horizon_model = std::make_shared<const Model>(with_implicit_damping(with_friction, implicit_step));
  auto plant_model = std::make_shared<const Model>(with_implicit_damping(with_friction, s.plant_step));
  OcpWeights weights = auto_weights(s, configurations, with_friction, stepped, dtau, lower, upper, notes);
  MatX<double> terminal = terminal_lqr(*horizon_model, s, solver, weights, dtau, notes);
  return HorizonSetup{std::move(plant_model), std::move(horizon_model), std::move(weights), solver, implicit, ratio,
                      lambda, std::move(eps), std::move(notes), std::move(terminal)};
}

}  // namespace idmpc
