#pragma once
/// @file stage_model.hpp
/// @brief The one stage interface of both formulations (as Crocoddyl's action models or
/// autogenu's OCP classes): a stage model knows a stage's dynamics and the derivatives of its
/// discrete Hamiltonian H_i = L(x_i, ·) + λ_{i+1}ᵀ v_i + γ_{i+1}ᵀ a_i, and owns the stages'
/// workspaces. FdStages and IdStages implement it, each with the derivative mode and the SIMD
/// lanes as template policies chosen once (OcpProblem picks the type), so no call branches on
/// formulation, mode or lanes.
///
/// One evaluation of the horizon's residual is one Evaluation token: every result a stage model
/// keeps between the calls of an evaluation (a stage's linearization, products computed in
/// lanes) is stamped with it and read only under the same token, so that nothing computed for
/// one evaluation can be taken for the next.

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/ocp/stage_terms.hpp"

namespace idmpc {

enum class Formulation { kForwardDynamics, kInverseDynamics };
enum class DerivativeMode { kMatrix, kAdjoint };

/// @brief Token of one evaluation of the horizon (OcpProblem::begin_evaluation).
struct Evaluation {
  std::uint64_t id = 0;
};

/// @brief The horizon's trajectories as the shooting scheme holds them, for the calls that
/// run across stages (columns 0 … stages − 1 are used).
struct StageTrajectories {
  int stages;
  const MatX<double>& q;    ///< n × (N+1) states
  const MatX<double>& v;
  MatX<double>& a;          ///< n × N accelerations: FD's outputs, ID's inputs
  MatX<double>& u;          ///< n × N joint torques: FD's inputs (zero on passive joints), ID's outputs
  const MatX<double>& rho;  ///< (m + n_e) × N multipliers: ρ of the limits, ν of the passive torques
  const MatX<double>* gmm;  ///< n × (N+1) given costates γ (multiple shooting), or null
};

class StageModel {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;
  using Out = Eigen::Ref<Vec>;

  using DualIn = Eigen::Ref<const VecX<Dual>>;
  using DualOut = Eigen::Ref<VecX<Dual>>;

  virtual ~StageModel() = default;
  virtual std::unique_ptr<StageModel> clone() const = 0;

  /// @brief Stage i's dynamics at (q, v) with its input: FD a = FD(q, v, u + d̂); ID
  /// u = ID(q, v, a) − d̂. The stage keeps its linearization for hamiltonian.
  virtual void dynamics(const StageTerms& terms, Evaluation ev, int i, In q, In v, In input, Out output) = 0;

  /// @brief Once the states of stages 0 … x.stages − 1 are known (after a rollout): what runs
  /// across stages. ID: every stage's dynamics (x.u out), with the products of each; FD: the
  /// stages' dynamics ran in the rollout, and what may run in lanes after it.
  virtual void at_states(const StageTerms& terms, Evaluation ev, StageTrajectories& x) = 0;

  /// @brief Every stage at given states and costates x.gmm (multiple shooting): its dynamics
  /// and whatever of its Hamiltonian is independent of the other stages there.
  virtual void at_costates(const StageTerms& terms, Evaluation ev, StageTrajectories& x) = 0;

  /// @brief F (size n + 2m) of stage i's Hamiltonian at its linearization of this evaluation,
  /// and with `state` hq = ∂H/∂q, hv = ∂H/∂v (OcpProblem::stage_hamiltonian).
  virtual void hamiltonian(const StageTerms& terms, Evaluation ev, int i, In q, In v, In a, In u, In d, In rho,
                           In lmd_next, In gmm_next, Out hq, Out hv, Out F, bool state) = 0;

  /// @brief Bytes of heap the stages' workspaces own (the per-stage ones and the lanes').
  virtual std::size_t workspace_bytes() const = 0;

  /// @brief dynamics and hamiltonian in dual numbers (formulations.md §Exact products): the same arithmetic as the
  /// stage's own in its derivative mode, stage by stage (never in lanes), each operation also
  /// carried on the tangents, so that the tangent parts are the exact directional derivatives.
  /// Needs reserve_dual first (std::logic_error otherwise); their kept linearizations are stamped
  /// with the evaluation as the double ones.
  virtual void dynamics(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn input,
                        DualOut output) = 0;
  virtual void hamiltonian(const StageTerms& terms, Evaluation ev, int i, DualIn q, DualIn v, DualIn a, DualIn u,
                           DualIn d, DualIn rho, DualIn lmd_next, DualIn gmm_next, DualOut hq, DualOut hv,
                           DualOut F, bool state) = 0;
  /// @brief Sizes the dual-number workspaces (one per stage) for `model`, the stages' own.
  virtual void reserve_dual(const Model& model) = 0;
  bool dual_reserved() const { return dual_reserved_; }

 protected:
  bool dual_reserved_ = false;
  void require_dual() const {
    if (!dual_reserved_) throw std::logic_error("stage model: dual-number evaluation without reserve_dual");
  }
};

namespace detail {

/// @brief The evaluation each stage's kept results belong to (0: none yet).
class StageStamps {
 public:
  explicit StageStamps(int N) : id_(static_cast<size_t>(N), 0) {}
  void stamp(int i, Evaluation ev) { id_[static_cast<size_t>(i)] = ev.id; }
  bool current(int i, Evaluation ev) const { return id_[static_cast<size_t>(i)] == ev.id; }
  /// @brief Throws std::logic_error unless stage i's results are of evaluation ev.
  void require(int i, Evaluation ev, const char* what) const {
    if (!current(i, ev)) {
      throw std::logic_error(std::string(what) + " of stage " + std::to_string(i) +
                             ": expected its results of this evaluation, got none");
    }
  }

 private:
  std::vector<std::uint64_t> id_;
};

}  // namespace detail
}  // namespace idmpc
