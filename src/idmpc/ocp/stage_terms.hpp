#pragma once
/// @file stage_terms.hpp
/// @brief What every stage of a problem shares, whatever its formulation: the model, the costs
/// with their torque reference, the torque bounds and the disturbance estimate (DESIGN §4, §8,
/// §10), and the parts of a stage's Hamiltonian that do not involve the dynamics. The stage
/// models (fd_stages.hpp, id_stages.hpp) add the dynamics' part.

#include <memory>

#include "idmpc/model/data.hpp"
#include "idmpc/ocp/cost.hpp"
#include "idmpc/ocp/torque_limits.hpp"

namespace idmpc {

class StageTerms {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;
  using Out = Eigen::Ref<Vec>;

  /// @brief Sets the cost's torque reference to u_ref = ID(q_ref, 0, 0). Throws
  /// std::invalid_argument on a null model, sizes that differ from the model's or bad limits.
  StageTerms(std::shared_ptr<const Model> model, QuadraticCost cost, const TorqueLimits& limits);

  const Model& model() const { return *model_; }
  const std::shared_ptr<const Model>& model_ptr() const { return model_; }
  int n() const { return model_->n; }
  int m() const { return bounds_.m(); }
  const QuadraticCost& cost() const { return cost_; }
  const TorqueBounds& bounds() const { return bounds_; }
  TorqueBounds& bounds() { return bounds_; }
  const Vec& disturbance() const { return d_hat_; }

  /// @brief d̂ (size n, finite; else std::invalid_argument); u_ref = ID(q_ref, 0, 0) − d̂.
  void set_disturbance(const Vec& d_hat);
  /// @brief q_ref (size n, finite; else std::invalid_argument); u_ref = ID(q_ref, 0, 0) − d̂.
  /// Allocation-free.
  void set_target(const Vec& q_ref);

  /// @brief w = ∂(L + ρᵀ(s∘c))/∂u = R(u − u_ref) + 2s∘ρ∘(u − ū) on the bounded joints (u, w
  /// size n; ρ size m).
  void torque_gradient(In u, In rho, Out w) const {
    cost_.torque_gradient(u, w);
    bounds_.add_torque_gradient(u, rho, w);
  }

  /// @brief torque_gradient for stages in SIMD lanes: u, w size n, ρ size m, of packs P.
  template <typename P> void torque_gradient(const VecX<P>& u, const VecX<P>& rho, VecX<P>& w) const {
    const VecX<double>& R = cost_.weights().R;
    const VecX<double>& u_ref = cost_.u_ref();
    for (int j = 0; j < n(); ++j) w[j] = R[j] * (u[j] - u_ref[j]);
    for (int k = 0; k < m(); ++k) {
      const int j = bounds_.joints()[static_cast<size_t>(k)];
      w[j] += (2.0 * bounds_.scale()[k]) * rho[k] * (u[j] - bounds_.middle()[k]);
    }
  }

  /// @brief The rest of stage i's block F_i once its first n rows hold ∂H/∂input: ∂H/∂d =
  /// −r_d + 2s∘ρ∘d and ∂H/∂ρ = s∘c; with `state` also hq = ∂L/∂q + gq and hv = ∂L/∂v + λ_{i+1}
  /// + gv (the Euler step q_{i+1} = q_i + Δτ v_i), for the dynamics' parts gq, gv of ∂H/∂q, ∂H/∂v.
  void close_stage(In q, In v, In u, In d, In rho, In lmd_next, In gq, In gv, Out hq, Out hv, Out F,
                   bool state) const {
    const int n = this->n(), m = this->m();
    if (m > 0) bounds_.dummy_gradients(u, d, rho, F.segment(n, m), F.segment(n + m, m));
    if (!state) return;
    cost_.state_gradient(q, v, hq, hv);
    hq += gq;
    hv += lmd_next + gv;
  }

 private:
  // u_ref = τ_ref − d̂ into the cost
  void update_torque_reference();

  std::shared_ptr<const Model> model_;
  QuadraticCost cost_;
  TorqueBounds bounds_;
  Vec d_hat_;      ///< disturbance estimate
  Vec zero_;       ///< v = a = 0 of the torque reference
  Vec tau_ref_;    ///< ID(q_ref, 0, 0)
  Vec u_ref_;      ///< ID(q_ref, 0, 0) − d̂, handed to the cost
  Data rnea_data_; ///< workspace of ID(q_ref, 0, 0)
};

}  // namespace idmpc
