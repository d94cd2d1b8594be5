// The paper's swing-up task on its 4-link arm for a few hundred control steps: the task file and
// model come from idmpc's data directory (IDMPC_DATA_DIR, or share/idmpc beside the executable),
// C/GMRES computes the torque, MuJoCo moves the arm. Prints max|q - qref| at the start and the end.
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>

#include "idmpc/experiment/task.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/solver/controller.hpp"

int main(int argc, char** argv) try {
  const long steps = argc > 1 ? std::atol(argv[1]) : 500;
  idmpc::mj::install_error_handlers();
  // the task (weights, horizon, C/GMRES settings) and its model
  const idmpc::Task& task = idmpc::paper_task();
  const idmpc::mj::LoadedModel loaded = idmpc::mj::load_model_translated(task.model);
  const mjModel* m = loaded.model.get();
  const idmpc::mj::ImportedModel imported = idmpc::mj::import_model(m, task.model);
  const idmpc::ResolvedTask r = idmpc::resolve(task, imported.model.n);

  // the controller on the imported model, the plant on MuJoCo's
  idmpc::Controller controller(
      idmpc::OcpProblem(imported.model, r.formulation, r.derivatives, r.weights, r.qref, task.N), r.cgmres);
  controller.set_torque_limits(imported.actuation.torque_lower, imported.actuation.torque_upper);
  idmpc::mj::Plant plant(m, imported.actuation);
  plant.set_control_period(r.cgmres.dt);
  plant.reset(r.q0, idmpc::VecX<double>::Zero(r.q0.size()));

  // each update at t yields the torque for the next period; the current one is applied meanwhile
  std::cout << "start: max|q - qref| = " << (plant.q() - r.qref).cwiseAbs().maxCoeff() << "\n";
  idmpc::VecX<double> tau = controller.initialize(plant.q(), plant.v());
  for (long k = 0; k < steps; ++k) {
    const bool ok = controller.update(static_cast<double>(k) * r.cgmres.dt, plant.q(), plant.v());
    std::string reason;
    if (!ok) reason = controller.failure();
    if (ok && !plant.step(tau, &reason)) reason = "plant: " + reason;
    if (!reason.empty()) {
      std::cerr << "closed_loop: diverged at step " << k << ": " << reason << "\n";
      return 1;
    }
    tau = controller.torque();
  }
  std::cout << "after " << steps << " steps (" << plant.time() << " s): max|q - qref| = "
            << (plant.q() - r.qref).cwiseAbs().maxCoeff() << "\n";
  return 0;
} catch (const std::exception& e) {
  std::cerr << "closed_loop: error: " << e.what() << "\n";
  return 1;
}
