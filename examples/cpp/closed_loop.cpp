// A MuJoCo loop of your own with an idmpc controller: the controller's settings come from a task
// file (model, target, weights, limits, the plant's friction and damping) as `idmpc swingup` makes
// them, here with the formulation and solver you choose; the simulation is plain MuJoCo, stepped
// here. Usage: closed_loop [TASK.json [STEPS [fd|id [cgmres|riccati|auto]]]] (default: the paper's
// swing-up task from idmpc's data directory, IDMPC_DATA_DIR or share/idmpc beside the executable;
// 1000 steps; the task's formulation and solver).
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>

#include <mujoco/mujoco.h>

#include "idmpc/mujoco/task_run.hpp"

int main(int argc, char** argv) try {
  const idmpc::Task task = argc > 1 ? idmpc::load_task(argv[1]) : idmpc::paper_task();
  const long steps = argc > 2 ? std::atol(argv[2]) : 1000;
  idmpc::mj::install_error_handlers();
  idmpc::mj::TaskRun run(task);  // throws one line naming the file, field or joint
  for (const std::string& line : run.notices()) std::cout << "note: " << line << "\n";

  // the controller `idmpc swingup` would run (run.controller()), or the same settings with
  // another formulation or solver: one settings type, the "auto" choices made by the controller
  idmpc::ControllerSettings settings = run.settings();
  if (argc > 3) settings.formulation = idmpc::parse_formulation(argv[3]);
  if (argc > 4) settings.solver = idmpc::parse_solver(argv[4]);
  idmpc::Controller controller(run.shared_model(), settings);
  std::cout << idmpc::to_string(controller.solver_kind()) << " (" << idmpc::to_string(settings.formulation) << ") on "
            << task.model << "\n";

  // your simulation: the task's model (newer MJCF translated for this MuJoCo as idmpc reads it),
  // stepped at the control period, the controller's joint torques applied directly
  const idmpc::mj::ModelPtr model = idmpc::mj::load_model(task.model);
  mjModel* m = model.get();
  m->opt.timestep = controller.dt();
  m->opt.disableflags |= mjDSBL_ACTUATION;
  mjData* d = mj_makeData(m);
  Eigen::Map<idmpc::VecX<double>> q(d->qpos, m->nq), v(d->qvel, m->nv), applied(d->qfrc_applied, m->nv);
  q = run.q0();
  mj_forward(m, d);

  // each update at t gives the torque for [t + dt, t + 2 dt); the previous one applies meanwhile
  idmpc::VecX<double> tau = controller.initialize(q, v);
  for (long k = 0; k < steps; ++k) {
    if (!controller.update(static_cast<double>(k) * controller.dt(), q, v)) {
      std::cerr << "closed_loop: diverged at t = " << d->time << " s: " << controller.failure() << "\n";
      return 3;
    }
    applied = tau;  // joint torques, within the actuators' range (the controller clamps)
    mj_step(m, d);
    tau = controller.torque();
  }
  std::cout << "after " << d->time << " s: max|q - q_ref| = " << (q - controller.q_ref()).cwiseAbs().maxCoeff()
            << "\n";
  mj_deleteData(d);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "closed_loop: " << e.what() << "\n";
  return 1;
}
