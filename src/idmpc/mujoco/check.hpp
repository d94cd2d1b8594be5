#pragma once
/// @file check.hpp
/// @brief Compares our dynamics with MuJoCo and our derivatives with central finite
/// differences at random states: the engine of `idmpc check` and of the dynamics tests.

#include <cmath>
#include <string>
#include <vector>

#include "idmpc/mujoco/hold.hpp"
#include "idmpc/mujoco/import.hpp"

namespace idmpc::mj {

/// @brief Tolerances (relative errors, see relative_error).
struct CheckTolerances {
  double mujoco = 1e-10;      ///< ID, FD, M against MuJoCo: same arithmetic up to rounding
  double derivative = 1e-6;   ///< analytic vs central differences (truncation ~h² ≈ 4e-11·f''')
  double adjoint = 1e-10;     ///< adjoints and consistency identities: exact up to rounding
};

struct CheckEntry {
  std::string quantity;  ///< e.g. "ID vs mj_inverse"
  double worst = 0;      ///< worst relative error over the samples; NaN once any was NaN
  double tolerance = 0;
  /// false for a NaN error
  bool ok() const { return worst <= tolerance; }
  /// @brief Keeps the worst error so far; a NaN error sticks (std::max would drop it).
  void record(double error) {
    if (std::isnan(worst)) return;
    if (std::isnan(error) || error > worst) worst = error;
  }
};

/// @brief ‖x − y‖∞ / max(‖y‖∞, 1): relative for the O(1)–O(100) quantities of robot models,
/// absolute where the reference is near zero. NaN if x or y has a non-finite entry (a
/// comparison of NaNs must fail), infinity if their sizes differ.
double relative_error(const MatX<double>& x, const MatX<double>& y);

/// @brief What the MuJoCo reference of check_model switches off because the controller's model
/// does not have it (and which would otherwise be reported as a mismatch): fluid forces (medium
/// density or viscosity), tendon springs and tendon dampers. Constraints (contacts, limits,
/// friction loss, equalities) and actuation are always off in the reference. Empty if the model
/// has none of them.
std::vector<std::string> reference_simplifications(const mjModel* m);

/// @brief Runs every comparison at `samples` random states drawn from `seed`, against MuJoCo
/// with the features of reference_simplifications switched off.
std::vector<CheckEntry> check_model(const mjModel* m, const Model& model, int samples,
                                    unsigned seed, const CheckTolerances& tol = {});

/// @brief For a model whose controller holds joints (hold.hpp): `model`, the controller's
/// model (the held joints welded), against MuJoCo on the whole model `full` with the held joints
/// where held and at rest (zero velocity and acceleration): its inverse dynamics and mass matrix
/// are the rows of the other dofs, exactly. `samples` random states from `seed`.
std::vector<CheckEntry> check_held(const mjModel* full, const HeldJoints& held, const Model& model, int samples,
                                   unsigned seed, const CheckTolerances& tol = {});

}  // namespace idmpc::mj
