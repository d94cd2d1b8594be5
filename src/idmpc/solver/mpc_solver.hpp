#pragma once
/// @file mpc_solver.hpp
/// @brief What the Controller drives, whatever the solver family: C/GMRES (cgmres.hpp: the
/// continuation of the optimality residual, one linear solve per update) or the Riccati
/// recursion (riccati.hpp: Gauss–Newton SQP on the stage local models). Each owns its problem;
/// the Controller applies the torque rule to the first stage's input and never asks which
/// solver it has.

#include <functional>
#include <memory>
#include <string>

#include "idmpc/ocp/problem.hpp"

namespace idmpc {

/// @brief The solver family: C/GMRES, or Gauss–Newton SQP with a Riccati recursion. kAuto is a
/// setting only (ControllerSettings::solver): the horizon setup resolves it on the model
/// (horizon_setup.hpp); no solver is of that kind.
enum class SolverKind { kCgmres, kRiccati, kAuto };
/// @brief "cgmres"/"riccati"/"auto"; parse throws std::invalid_argument naming the value.
std::string to_string(SolverKind s);
SolverKind parse_solver(const std::string& s);

/// @brief Wall-clock split of one update [s]. C/GMRES: the residual's forward sweeps, its
/// backward sweeps, the rest (GMRES). Riccati: the stage local models (dynamics, derivatives,
/// costs), the Riccati recursion and the step along it, the rest (line search, bookkeeping).
struct UpdateTimes {
  double total = 0;
  double rollout = 0;
  double costate = 0;
  double gmres = 0;
};

class MpcSolver {
 public:
  using Vec = VecX<double>;
  using In = Eigen::Ref<const Vec>;

  virtual ~MpcSolver() = default;
  virtual SolverKind kind() const = 0;
  virtual OcpProblem& problem() = 0;
  virtual const OcpProblem& problem() const = 0;
  /// @brief The sampling period Δt the solver assumes between updates.
  virtual double dt() const = 0;

  /// @brief The start at time t from the measured (q, v); returns the optimality error reached.
  /// Throws std::runtime_error when the start is non-finite.
  virtual double initialize(double t, In q, In v) = 0;
  /// @brief One control update at time t from the measured (q, v); false on divergence, with
  /// failure() saying why.
  virtual bool update(double t, In q, In v) = 0;
  /// @brief The first stage's input of the current solution: the torque u_0 (FD) or the
  /// acceleration a_0 (ID).
  virtual const Vec& first_input() const = 0;

  virtual const std::string& failure() const = 0;
  /// @brief The optimality error of the solution at the start of the last update (each family's
  /// own measure of it: docs/solvers.md).
  virtual double residual_norm() const = 0;
  /// @brief How far the stage torques of the last update's solution leave their bounds [N m].
  virtual double constraint_violation() const = 0;
  /// @brief Evaluations of the horizon in the last update (C/GMRES: of F; Riccati: of the stage
  /// local models and of the line search's values).
  virtual int evaluations() const = 0;
  virtual const UpdateTimes& last_times() const = 0;
  virtual void enable_timing(bool on) = 0;
  /// @brief A function initialize calls between the iterations of its start, which may take
  /// seconds (a full-horizon C/GMRES start on a long horizon, many Riccati start iterations):
  /// it may throw to abandon the start (Ctrl-C in Python), and the exception leaves initialize
  /// (initialize again before the next update). Throw something other than a
  /// std::runtime_error, which initialize reports as a failed start. Empty: none.
  virtual void set_interrupt_check(std::function<void()> check) = 0;
};

}  // namespace idmpc
