#include "idmpc/experiment/horizon_setup.hpp"

#include <algorithm>
#include <cmath>
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
OcpWeights auto_weights(const ResolvedTask& r, bool frame_target, const Model& model, const Model& stepped,
                        double dtau, const VecX<double>& lower, const VecX<double>& upper,
                        std::vector<std::string>& notes) {
  OcpWeights w = r.weights;
  const int n = model.n;
  if (w.Qq.size() == 0) w.Qq = VecX<double>::Constant(n, frame_target ? kAutoPostureQq : kAutoQq);
  if (w.Qv.size() == 0) w.Qv = VecX<double>::Constant(n, frame_target ? kAutoPostureQv : kAutoQv);
  if (w.R.size() == 0) {
    Data data(model);
    const VecX<double> zero = VecX<double>::Zero(n);
    const VecX<double> hold = rnea(model, data, r.qref, zero, zero);
    const VecX<double> inertia = crba(model, data, r.qref).diagonal();
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
    const VecX<double> inv_inertia = inverse_inertia_diagonal(stepped, {r.q0, r.qref});
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

HorizonSetup setup_horizon(const Task& task, const ResolvedTask& r, const Model& model,
                           const VecX<double>& friction_loss, const VecX<double>& lower,
                           const VecX<double>& upper, double plant_step) {
  const int n = model.n;
  if (friction_loss.size() != n || lower.size() != n || upper.size() != n || r.q0.size() != n ||
      r.qref.size() != n) {
    throw std::invalid_argument("horizon setup: friction, limits, q0 and q_ref must have " + std::to_string(n) +
                                " entries");
  }
  std::vector<std::string> notes;
  const double dtau = task.Tf / task.N;
  const std::vector<VecX<double>> configurations = {r.q0, r.qref};

  // damping: explicit unless asked for, or unstable with "auto"
  const double ratio = dtau * damping_rate(model, configurations);
  bool implicit = task.implicit_damping == "on";
  if (task.implicit_damping == "auto" && ratio > 1) {
    if (task.alpha == 0) {
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

  // friction loss: f·tanh(v/ε), ε given or the smallest with a stable explicit step
  VecX<double> eps = VecX<double>::Zero(n);
  if ((friction_loss.array() > 0).any()) {
    if (r.friction_velocity.size() == n) {
      eps = r.friction_velocity;
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
                    (r.friction_velocity.size() == n ? "(given)" : "(\"auto\": the smallest with a stable explicit step)"));
  }
  const Model with_friction = with_joint_friction(model, friction_loss.cwiseMax(0.0), eps);
  Model horizon_model = with_implicit_damping(with_friction, implicit_step);
  Model plant_model = with_implicit_damping(with_friction, plant_step);
  OcpWeights weights = auto_weights(r, task.target.has_value(), with_friction, stepped, dtau, lower, upper, notes);
  return HorizonSetup{std::move(plant_model), std::move(horizon_model), std::move(weights), implicit, ratio,
                      std::move(eps), std::move(notes)};
}

}  // namespace idmpc
