#pragma once
/// @file problems.hpp
/// @brief Shared fixtures of the OCP and solver tests: a loaded model, the paper's weights,
/// seeded random vectors.

#include <random>
#include <string>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/ocp/problem.hpp"

namespace idmpc::test {

/// @brief A MuJoCo model and the controller's Model imported from it.
struct Problem {
  mj::ModelPtr m;
  Model model;
};

/// @brief Loads and imports a model file as the controller sees it, a gripper's held joints
/// welded (hold.hpp); throws like the CLI would.
Problem load_problem(const std::string& path);

/// @brief The paper's weights (mjcf/paper_swingup.json) with Q_a set to `Qa`.
OcpWeights paper_weights(int n, double Qa = 0.0);

/// @brief n values uniform in [lo, hi].
VecX<double> random_vector(std::mt19937& rng, int n, double lo, double hi);
/// @brief n values uniform in [−scale, scale].
inline VecX<double> random_vector(std::mt19937& rng, int n, double scale) {
  return random_vector(rng, n, -scale, scale);
}

}  // namespace idmpc::test
