#include "support/problems.hpp"

#include <utility>

#include "idmpc/mujoco/import.hpp"

namespace idmpc::test {

Problem load_problem(const std::string& path) {
  mj::ModelPtr m = mj::load_model(path);
  Model model = mj::import_model(m.get(), path).model;
  return {std::move(m), std::move(model)};
}

OcpWeights paper_weights(int n, double Qa) {
  return {VecX<double>::Constant(n, 1.0), VecX<double>::Constant(n, 0.1),
          VecX<double>::Constant(n, Qa), VecX<double>::Constant(n, 1e-4)};
}

VecX<double> random_vector(std::mt19937& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  VecX<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng);
  return x;
}

}  // namespace idmpc::test
