#include "support/problems.hpp"

#include <utility>

#include "idmpc/experiment/task.hpp"
#include "idmpc/mujoco/hold.hpp"
#include "idmpc/mujoco/import.hpp"

namespace idmpc::test {

Problem load_problem(const std::string& path) {
  // the controller's model: a gripper's held joints welded (hold.hpp)
  mj::ControllerModel models = mj::load_controller_model(path);
  mj::ModelPtr m = std::move(models.held.empty() ? models.full.model : models.welded.model);
  Model model = mj::import_model(m.get(), path).model;
  return {std::move(m), std::move(model)};
}

OcpWeights paper_weights(int n, double Qa) {
  OcpWeights w = resolve(paper_task(), n).controller.weights;
  w.Qa.setConstant(Qa);
  return w;
}

VecX<double> random_vector(std::mt19937& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  VecX<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng);
  return x;
}

}  // namespace idmpc::test
