#pragma once
/// @file local_model.hpp
/// @brief A stage's local model: what a Newton-type solver with a Riccati recursion reads (as
/// Crocoddyl's action data or acados' stage QP), from the same costs, dynamics and bounds as
/// C/GMRES's stage Hamiltonian (stage_terms.hpp) and from the analytic derivatives only.
///
/// Stage i with state x = (q, v) (2n), input u (FD: the n_u actuators' torques; ID: the n
/// accelerations) and step Δτ, explicit Euler as everywhere in idmpc:
///   x⁺ = f(x, u) = (q + Δτ v, v + Δτ a),   FD: a = FD(q, v, Sᵀu + d̂);   ID: a = u,
///   τ(x, u) = FD: Sᵀu;   ID: ID(q, v, u) − d̂   (the joint torques: the actuated ones bounded),
/// with S the selection of the actuated joints (S = I on a fully actuated model). On an
/// under-actuated model ID's passive rows τ_E(x, u) are the stage's equality constraint
/// τ_E = 0, which the solver reads from τ, τ_x, τ_u (it eliminates it: riccati.hpp).
///   ℓ(x, u) = Δτ [½‖q − q_ref,i‖²_Qq + ½‖v − v_ref,i‖²_Qv + φ_frame,i(q) + ½‖τ − u_ref,i‖²_R (+ ½‖a‖²_Qa, ID)]
/// so that Σ ℓ_i + φ(x_N) is the discrete objective whose input gradient, divided by Δτ, is
/// C/GMRES's residual F (the two solvers solve one problem). The local model at (x, u):
///   f, A = ∂f/∂x, B = ∂f/∂u;  ℓ, ℓ_x, ℓ_u, and the Gauss–Newton Hessian (L_xx, L_uu, L_ux);
///   τ, τ_x = ∂τ/∂x, τ_u = ∂τ/∂u.
/// FD: A's lower rows are Δτ(∂a/∂q, ∂a/∂v) and B's Δτ M⁻¹Sᵀ (ABA derivatives); τ_x = 0, τ_u = Sᵀ.
/// ID: A and B are constant (the dynamics are linear in (x, a)); τ_x = (∂ID/∂q, ∂ID/∂v), τ_u = M
/// (RNEA derivatives), so the torque cost's Gauss–Newton Hessian is dense: τ'ᵀ R τ'.
///
/// The torque term is kept apart (add_torque_terms): a solver that weights τ further (a
/// constraint's barrier or penalty) adds its weight there and pays for τ'ᵀWτ' once.
/// Every model term of the dynamics kernels is in f and τ (armature, damping and implicit
/// damping, stiffness, smooth friction, d̂), and every reference moves with the stage times
/// (StageTerms::set_stage_times).

#include <memory>
#include <vector>

#include "idmpc/model/data.hpp"
#include "idmpc/ocp/stage_terms.hpp"

namespace idmpc {

/// @brief One stage's local model (sizes: nx = 2n, nu = the input's: n unless FD is
/// under-actuated).
struct StageLocal {
  VecX<double> x_next;          ///< f(x, u)
  MatX<double> A, B;            ///< ∂f/∂x (2n × 2n), ∂f/∂u (2n × nu)
  double cost = 0;              ///< ℓ(x, u)
  VecX<double> l_x, l_u;        ///< ∂ℓ/∂x, ∂ℓ/∂u
  MatX<double> L_xx, L_uu, L_ux;  ///< Gauss–Newton Hessian (L_ux: nu × nx)
  VecX<double> tau;             ///< τ(x, u)
  MatX<double> tau_x, tau_u;    ///< ∂τ/∂x (n × 2n), ∂τ/∂u (n × nu)

  /// @param nu the input's size (< 0: n)
  explicit StageLocal(int n = 0, int nu = -1);
};

/// @brief The terminal cost's local model: φ(x_N), its gradient and Gauss–Newton Hessian.
struct TerminalLocal {
  double cost = 0;
  VecX<double> l_x;
  MatX<double> L_xx;
  explicit TerminalLocal(int n = 0) : l_x(VecX<double>::Zero(2 * n)), L_xx(MatX<double>::Zero(2 * n, 2 * n)) {}
};

/// @brief A formulation's stage as a Riccati-type solver reads it. One instance is one
/// workspace (use one per thread); it reads the StageTerms it is given and writes nothing of
/// them. A new formulation (or integrator) is another subclass.
class LocalModel {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;
  using Out = Eigen::Ref<Vec>;

  virtual ~LocalModel() = default;
  virtual std::unique_ptr<LocalModel> clone() const = 0;

  int n() const { return n_; }
  int nx() const { return 2 * n_; }
  /// @brief The input's size: n, or n_u for FD on an under-actuated model.
  int nu() const { return nu_; }
  /// @brief Whether A and B are the same at every point (ID: the Euler step of a = u).
  virtual bool linear_dynamics() const = 0;
  /// @brief Whether τ is the input itself, scattered to its joints (FD): τ_x = 0, τ_u = Sᵀ.
  virtual bool torque_is_input() const = 0;

  /// @brief Stage i's local model at (x, u) without the torque term of the cost (add_torque_terms
  /// adds it). Allocation-free once `out` is sized (StageLocal(n, nu())).
  virtual void linearize(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out) = 0;
  /// @brief L += τ'ᵀ diag(W) τ' and (ℓ_x, ℓ_u) += τ'ᵀ g, τ' = (τ_x, τ_u), after linearize.
  virtual void add_torque_terms(In W, In g, StageLocal& out) = 0;

  /// @brief The whole local model: linearize, then the torque cost Δτ·½‖τ − u_ref,i‖²_R.
  void local_model(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out);

  /// @brief Values only (a line search): x⁺ = f(x, u), τ(x, u); returns ℓ(x, u) with its torque
  /// term.
  virtual double evaluate(const StageTerms& terms, int i, double dtau, In x, In u, Out x_next, Out tau) = 0;

  /// @brief The terminal cost at stage `stages` = N (its references): value, gradient, Hessian
  /// (with a terminal weight P: ½eᵀPe, Hessian P).
  void terminal(const StageTerms& terms, int stages, In x, TerminalLocal& out);
  /// @brief The terminal cost's value alone (StageTerms::terminal_cost).
  double terminal_cost(const StageTerms& terms, int stages, In x);

 protected:
  LocalModel(const StageTerms& terms, int nu);
  LocalModel(const LocalModel& o);
  LocalModel& operator=(const LocalModel&) = delete;

  /// The state part of stage i's cost, scaled by `scale`: value, ℓ_x, L_xx (overwritten).
  double state_terms(const StageTerms& terms, int i, double scale, In x, Out l_x, Eigen::Ref<MatX<double>> L_xx);
  /// ½‖τ − u_ref,i‖²_R, R(τ − u_ref,i) of stage i
  static double torque_cost(const StageTerms& terms, int i, In tau, Out g);

  int n_, nu_;
  StageTerms::FrameScratch<double> frame_;
  Vec q_, v_, lq_, lv_, hvv_, g_, W_;
};

/// @brief The forward-dynamics stage: u is the actuators' torque, a = FD(q, v, Sᵀu + d̂) by ABA,
/// its derivatives by the ABA derivatives (∂a/∂q, ∂a/∂v, M⁻¹ and its actuated columns).
class FdLocalModel final : public LocalModel {
 public:
  explicit FdLocalModel(const StageTerms& terms);
  std::unique_ptr<LocalModel> clone() const override { return std::make_unique<FdLocalModel>(*this); }
  bool linear_dynamics() const override { return false; }
  bool torque_is_input() const override { return true; }
  void linearize(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out) override;
  void add_torque_terms(In W, In g, StageLocal& out) override;
  double evaluate(const StageTerms& terms, int i, double dtau, In x, In u, Out x_next, Out tau) override;

 private:
  // τ = Sᵀu: the input's entries on their joints (the passive joints' torque zero)
  void scatter(In u, Out tau) const;

  Data data_;
  Vec torque_;
  std::vector<int> joints_;  ///< the joint of each input entry (Model::actuated_joints)
};

/// @brief The inverse-dynamics stage: u is the acceleration, τ = ID(q, v, u) − d̂ by RNEA, its
/// derivatives by the RNEA derivatives (∂ID/∂q, ∂ID/∂v, M).
class IdLocalModel final : public LocalModel {
 public:
  explicit IdLocalModel(const StageTerms& terms);
  std::unique_ptr<LocalModel> clone() const override { return std::make_unique<IdLocalModel>(*this); }
  bool linear_dynamics() const override { return true; }
  bool torque_is_input() const override { return false; }
  void linearize(const StageTerms& terms, int i, double dtau, In x, In u, StageLocal& out) override;
  void add_torque_terms(In W, In g, StageLocal& out) override;
  double evaluate(const StageTerms& terms, int i, double dtau, In x, In u, Out x_next, Out tau) override;

 private:
  Data data_;
  Vec a_;
  MatX<double> Wt_;  ///< diag(W)·τ' (n × 3n)
};

}  // namespace idmpc
