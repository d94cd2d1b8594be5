#pragma once
/// @file check.hpp
/// @brief Compares our dynamics with MuJoCo and our derivatives with central finite
/// differences at random states: the engine of `idmpc check` and of the dynamics tests.

#include <string>
#include <vector>

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
  double worst = 0;      ///< worst relative error over the samples
  double tolerance = 0;
  bool ok() const { return worst <= tolerance; }
};

/// @brief ‖x − y‖∞ / max(‖y‖∞, 1): relative for the O(1)–O(100) quantities of robot models,
/// absolute where the reference is near zero.
double relative_error(const MatX<double>& x, const MatX<double>& y);

/// @brief Runs every comparison at `samples` random states drawn from `seed`.
std::vector<CheckEntry> check_model(const mjModel* m, const Model& model, int samples,
                                    unsigned seed, const CheckTolerances& tol = {});

}  // namespace idmpc::mj
