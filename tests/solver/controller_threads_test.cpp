// The threading contract (docs/install.md, "Threads"): separate Controller instances run on
// separate threads with nothing shared but the models and the references, which are only read.
// Four closed loops -- both solver families, both formulations, one frame target moving on one
// shared circle, one shared model -- run at once, each on its own thread with its own MuJoCo
// plant, and must give bit for bit the torques each gives alone. Under ThreadSanitizer
// (tools/sanitize.sh --thread) any data race between them is a report, and the job fails.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/mujoco/closed_loop.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/plant.hpp"
#include "idmpc/ocp/trajectory.hpp"
#include "idmpc/solver/controller.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

constexpr const char* kPanda = IDMPC_SOURCE_DIR "/mjcf/panda.xml";

struct Job {
  SolverKind solver;
  Formulation formulation;
  DerivativeMode derivatives;
};

std::string name(const Job& job) {
  return to_string(job.solver) + "/" + to_string(job.formulation) + "/" + to_string(job.derivatives);
}

// What every job shares, read only: the MuJoCo model (each plant copies it), the imported model
// and the moving reference of the frame target
struct Shared {
  test::Problem problem = test::load_problem(kPanda);
  std::shared_ptr<const Model> model = std::make_shared<const Model>(problem.model);
  mj::Actuation actuation = mj::import_model(problem.m.get(), kPanda).actuation;
  FrameTarget target;
  std::shared_ptr<const Trajectory> circle;
  VecX<double> q0;

  Shared() {
    const int n = model->n;
    q0 = VecX<double>::Zero(n);
    q0[3] = -1.6;  // elbow bent: the flange away from singular postures
    q0[5] = 1.6;
    const int body = model->n - 1;
    target.frame = Frame{"flange", body, Transform<double>{}};
    target.position_weight = Vec3<double>::Constant(1e3);
    target.orientation_weight = 10;
    FrameKinematics<double> fk(*model, target.frame);
    fk.compute(*model, q0);
    target.position = fk.position();
    target.rotation = fk.rotation();
    circle = std::make_shared<CircleTrajectory>(fk.position(), Vec3<double>(0, 0, 1), 0.05, 1.0,
                                                Vec3<double>(1, 0, 0), 0.0);
  }

  ControllerSettings settings(const Job& job) const {
    const int n = model->n;
    ControllerSettings s;
    s.solver = job.solver;
    s.formulation = job.formulation;
    s.derivatives = job.derivatives;
    s.N = 10;
    s.cgmres.Tf = 0.3;
    s.cgmres.dt = 2e-3;
    s.weights = OcpWeights{VecX<double>::Constant(n, 1.0), VecX<double>::Constant(n, 1.0),
                           VecX<double>::Constant(n, job.formulation == Formulation::kInverseDynamics ? 1e-4 : 0.0),
                           VecX<double>::Constant(n, 1e-3)};
    s.q_ref = q0;
    s.frame_target = target;
    s.frame_reference = circle;
    s.torque_lower = VecX<double>::Constant(n, -80);
    s.torque_upper = VecX<double>::Constant(n, 80);
    s.observer_time_constant = 0.05;
    return s;
  }
};

// Holds each thread until all have built their controller and plant, so that the closed loops
// run at the same time (a race needs them interleaved: building them copies the shared models'
// reference counts, whose atomics order everything before them)
class StartGate {
 public:
  explicit StartGate(int threads) : waiting_(threads) {}
  void arrive_and_wait() {
    waiting_.fetch_sub(1);
    while (waiting_.load() > 0) std::this_thread::yield();
  }

 private:
  std::atomic<int> waiting_;
};

// One job's closed loop on its own plant and controller: the torque of every step
std::vector<VecX<double>> run(const Shared& shared, const Job& job, StartGate* gate = nullptr) {
  Controller controller(shared.model, shared.settings(job));
  mj::Plant plant(shared.problem.m.get(), shared.actuation);
  mj::ClosedLoopSettings ls;
  ls.duration = 0.1;
  ls.q0 = shared.q0;
  ls.v0 = VecX<double>::Zero(shared.model->n);
  ls.phase_timing = false;
  std::vector<VecX<double>> torques;
  if (gate) gate->arrive_and_wait();
  const mj::RunResult r = mj::run_closed_loop(plant, controller, ls, [&](const mj::StepRecord& s) { torques.push_back(s.u); });
  EXPECT_FALSE(r.diverged) << name(job) << ": " << r.divergence_reason;
  return torques;
}

TEST(ControllerThreads, SeparateInstancesOnThreadsGiveWhatEachGivesAlone) {
  const Shared shared;
  const std::vector<Job> jobs = {
      {SolverKind::kCgmres, Formulation::kForwardDynamics, DerivativeMode::kAdjoint},
      {SolverKind::kCgmres, Formulation::kInverseDynamics, DerivativeMode::kMatrix},
      {SolverKind::kRiccati, Formulation::kForwardDynamics, DerivativeMode::kAdjoint},
      {SolverKind::kRiccati, Formulation::kInverseDynamics, DerivativeMode::kAdjoint},
  };
  std::vector<std::vector<VecX<double>>> alone;
  for (const Job& job : jobs) alone.push_back(run(shared, job));

  // a few rounds: how the threads interleave varies, and a race shows only where they do
  for (int round = 0; round < 4; ++round) {
    std::vector<std::vector<VecX<double>>> together(jobs.size());
    std::vector<std::thread> threads;
    StartGate gate(static_cast<int>(jobs.size()));
    for (size_t i = 0; i < jobs.size(); ++i) threads.emplace_back([&, i] { together[i] = run(shared, jobs[i], &gate); });
    for (std::thread& t : threads) t.join();

    for (size_t i = 0; i < jobs.size(); ++i) {
      SCOPED_TRACE(name(jobs[i]) + ", round " + std::to_string(round));
      ASSERT_EQ(alone[i].size(), 50u);
      ASSERT_EQ(together[i].size(), alone[i].size());
      for (size_t k = 0; k < alone[i].size(); ++k) EXPECT_EQ(together[i][k], alone[i][k]) << "step " << k;
    }
  }
  // the jobs differ: a thread reading another's state would show
  EXPECT_NE(alone[0].back(), alone[1].back());
  EXPECT_NE(alone[2].back(), alone[3].back());
}

}  // namespace
}  // namespace idmpc
