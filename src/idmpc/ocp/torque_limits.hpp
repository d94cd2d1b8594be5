#pragma once
/// @file torque_limits.hpp
/// @brief Torque limits u_min ≤ u ≤ u_max as formulations.md §Torque limits puts them into C/GMRES (Ohtsuka 2004,
/// autogenu's control-input bounds): for each bounded joint j a dummy input d_j and a
/// multiplier ρ_j join the stage's unknowns, with the equality constraint and the dummy's cost
///   s_j c_j = 0,  c_j = (u_j − ū_j)² + d_j² − (Δ_j/2)²,  ū = (u_max + u_min)/2,  Δ = u_max − u_min
///   L += −r_d,j d_j.
/// The stage Hamiltonian gains ρᵀ(s∘c) − r_dᵀd, hence
///   ∂H/∂u_j += 2 s_j ρ_j (u_j − ū_j),   ∂H/∂d_j = −r_d,j + 2 s_j ρ_j d_j,   ∂H/∂ρ_j = s_j c_j.
///
/// Scaling (the plain form has s = 1): s_j = R_j / Δ_j states the same constraint in
/// the units of the torque gradient R(u − u_ref) — ρ is the plain multiplier divided by s. With
/// s = 1 the rows c (torque², ~10³–10⁴ on an arm) swamp the input rows (~R·torque) and neither
/// C/GMRES's kmax = 10 GMRES nor the Newton start can solve the stage block (measured on the
/// Panda: the initialization stalls at ‖F‖ ≈ 10, the closed loop diverges).
///
/// Capped at the input's block: s_j = min(R_j, C_j)/Δ_j (cap_scale), C_j the diagonal of the
/// input's block of ∂F/∂U (OcpProblem::cap_limit_rows). The constraint and the optimum are the
/// same for any s > 0; s sets where the rows (d, ρ) sit in ∂F/∂U: at about ±s_jΔ_j. FD's block
/// holds R_j and more (C_j ≥ R_j), so the cap never binds there. ID's acceleration block holds
/// R_j only through M: its diagonal is (MᵀRM)_jj plus the horizon's weights, and on light joints,
/// whose automatic R is large, R_j exceeds it by up to 1e3 — ten GMRES iterations did not resolve
/// that spread, and ID's continuation diverged on 7 of 36 generated arms (reach), against 3
/// with the cap (results.md#generated-arms-with-the-defaults).
///
/// Dummy weight: r_d,j = κ R_j Δ_j / 2 with κ = kDummyWeight. Eliminating d and ρ leaves the
/// barrier −r_d·√((Δ/2)² − (u − ū)²) on the torque: its curvature mid-range is κR (κ of the
/// torque weight), and at a holding torque u_ref ≠ ū it pulls the optimum off the target, by
/// ∝ κR/Q_q. Measured on the Panda reach (closed loop, 5 s, T_f = 1, Q_q = 100, Q_v = 10,
/// R = 1e-3): final error 8.5e-5 rad with κ = 1e-2, 8.4e-4 with κ = 0.1; κ = 1e-3 leaves a
/// corner so sharp where a bound becomes active (d ≈ r_d(u − ū)/push) that the ID loop diverged
/// at 0.46 s. With κ = 1e-2: 5.0e-4 rad at Q_q/R = 1e4, 2.6e-3 at Q_q/R = 1e3 (T_f = 0.5).

#include <vector>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

/// @brief Lower and upper torque of every joint (size n each), or both empty for no limits.
/// A joint with lower = −∞ and upper = +∞ is unbounded; a bounded joint needs both finite.
struct TorqueLimits {
  VecX<double> lower, upper;
};

/// @brief The bounded joints of a TorqueLimits, with what their constraints need.
class TorqueBounds {
 public:
  using In = Eigen::Ref<const VecX<double>>;
  using Out = Eigen::Ref<VecX<double>>;

  /// @brief κ of r_d,j = κ R_j Δ_j / 2 (see the file comment).
  static constexpr double kDummyWeight = 1e-2;
  /// @brief d is never set below this fraction of Δ/2 by consistent_dummy: at d = 0 the
  /// constraint's gradient in (u, d) vanishes with u at the bound, and ρ = r_d / 2sd blows up.
  static constexpr double kMinimumDummy = 1e-2;

  /// @brief Validates the limits of an n-joint problem with torque weights R (size n): throws
  /// std::invalid_argument naming the joint whose limit is NaN, one-sided or not lower < upper,
  /// or whose R is not positive while bounded (r_d and s would vanish), or naming wrong sizes.
  TorqueBounds(const TorqueLimits& limits, const VecX<double>& R, int n);

  /// @brief m: number of bounded joints.
  int m() const { return static_cast<int>(joint_.size()); }
  /// @brief Joint index of each bounded torque (size m, increasing).
  const std::vector<int>& joints() const { return joint_; }
  const VecX<double>& middle() const { return middle_; }          ///< ū, size m
  const VecX<double>& half_range() const { return half_range_; }  ///< Δ/2, size m
  const VecX<double>& scale() const { return scale_; }            ///< s = R/Δ (or capped), size m
  const VecX<double>& r_d() const { return r_d_; }                ///< dummy weights, size m

  /// @brief r_d = f·κRΔ/2 (f ≥ 1 pushes the solution into the interior, as a barrier weight;
  /// the initialization continues f down to 1).
  void set_dummy_weight_factor(double f) { r_d_ = f * r_d_nominal_; }
  /// @brief s_j = min(s_j, C_j/Δ_j) for the bounded joints j (C size n, positive where bounded;
  /// else std::invalid_argument naming the joint): rows no larger than the input's own.
  void cap_scale(const VecX<double>& C);

  /// @brief w_j += 2 s_k ρ_k (u_j − ū_k) for the bounded joints j = joints()[k] (u, w size n).
  /// For double or dual-number vectors (Eigen expressions).
  template <typename U, typename Rho, typename W> void add_torque_gradient(const U& u, const Rho& rho, W&& w) const {
    for (int k = 0; k < m(); ++k) {
      const int j = joint_[static_cast<size_t>(k)];
      w[j] += 2 * scale_[k] * rho[k] * (u[j] - middle_[k]);
    }
  }

  /// @brief ∂H/∂d = −r_d + 2s∘ρ∘d and ∂H/∂ρ = s∘c (u size n; d, rho, H_d, H_rho size m).
  /// For double or dual-number vectors (Eigen expressions).
  template <typename U, typename D, typename Rho, typename HD, typename HRho>
  void dummy_gradients(const U& u, const D& d, const Rho& rho, HD&& H_d, HRho&& H_rho) const {
    for (int k = 0; k < m(); ++k) {
      const auto e = u[joint_[static_cast<size_t>(k)]] - middle_[k];
      H_d[k] = -r_d_[k] + 2 * scale_[k] * rho[k] * d[k];
      H_rho[k] = scale_[k] * (e * e + d[k] * d[k] - half_range_[k] * half_range_[k]);
    }
  }

  /// @brief (d, ρ) consistent with the torque u (size n): d = √((Δ/2)² − (u − ū)²), at least
  /// kMinimumDummy·Δ/2, and ρ = r_d / 2sd, so that ∂H/∂d = 0 and, where u is inside the range
  /// by more than that, ∂H/∂ρ = 0; both d and ρ > 0.
  void consistent_dummy(In u, Out d, Out rho) const;

  /// @brief How far the torques u (n × stages, one column per stage) leave the bounds: the
  /// largest max(u_j − u_max,j, u_min,j − u_j, 0) over bounded joints and stages [N m].
  double violation(const Eigen::Ref<const MatX<double>>& u) const;

 private:
  std::vector<int> joint_;
  VecX<double> middle_, half_range_, scale_, r_d_nominal_, r_d_;
};

}  // namespace idmpc
