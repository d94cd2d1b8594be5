// The delay compensation of the ID controller (paper eqs. 27–28, formulations.md §The torque rule) in the closed loop
// with the MuJoCo plant, on the paper's swing-up of the 4-link arm.
//
// The update at t_k computes the torque the plant applies over [t_{k+1}, t_{k+2}), when the
// plant is no longer at the measured x(t_k): it has moved on under the torque of the previous
// update. The ID rule τ = ID(q + Δt v, v + Δt â_0, a_0) evaluates inverse dynamics at the state
// predicted for t_{k+1}, so that the plant (whose dynamics the model is) executes the planned
// acceleration a_0 over that period. What the compensation buys is thus measurable on the plant
// alone: its acceleration over [t_{k+1}, t_{k+2}), (v_{k+2} − v_{k+1})/Δt, is the a_0 planned
// at t_k. Evaluated at the measured state instead, the torque misses by ∂ID/∂x·Δt·ẋ, and the
// plant's acceleration by M⁻¹ of that: O(Δt) against the O(Δt²) of the prediction's own error
// (q predicted with v_k where the semi-implicit Euler step moves it with v_{k+1}).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/rnea.hpp"
#include "idmpc/experiment/task.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc {
namespace {

constexpr double kDuration = 0.4;  // s: from hanging at rest into the fast swing (|v| ≈ 3–7 rad/s)
// the start is left out: the arm is at rest there (nothing to compensate) while the start-up
// transient's accelerations (up to 2e3 rad/s²) make the O(Δt²) error largest
constexpr double kFrom = 0.02;  // s
// measured, relative RMS of the executed minus the planned acceleration over the window: 2.9e-4
// with the compensation; without it 9.8e-3 (3.6e-3 without the velocity prediction alone, 6.5e-3
// without the position prediction alone)
constexpr double kMiss = 1e-3;

struct LoopLog {
  std::shared_ptr<const Model> model;  // the plant's
  std::vector<double> t;
  std::vector<VecX<double>> q, v, a0;  // measured state and the a_0 planned by each update
  double dt = 0;
};

LoopLog run_swingup() {
  Task task = paper_task();
  task.model = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
  task.formulation = "id";
  task.derivatives = "adjoint";
  task.duration = kDuration;
  mj::TaskRun run(task);
  mj::ClosedLoopSettings ls = run.loop_settings();
  ls.phase_timing = false;
  LoopLog out;
  out.model = run.shared_model();
  out.dt = run.controller().dt();
  const mj::RunResult res = run.run(ls, [&](const mj::StepRecord& s) {
    out.t.push_back(s.t);
    out.q.push_back(s.q);
    out.v.push_back(s.v);
    // after the update at s.t: the a_0 of its solution, executed over [t + Δt, t + 2Δt)
    out.a0.push_back(run.controller().applied_acceleration());
  });
  EXPECT_FALSE(res.diverged) << res.divergence_reason << " at " << res.diverged_at;
  EXPECT_EQ(res.steps, std::lround(kDuration / out.dt));
  return out;
}

// √(Σ‖executed − planned‖²) / √(Σ‖planned‖²) over the periods [t_k, t_{k+1}) from kFrom on,
// `executed(k)` the plant's acceleration over the period and the plan the a_0 of the update at
// t_{k−1}
template <typename F> double relative_miss(const LoopLog& r, F&& executed) {
  double miss = 0, planned = 0;
  for (size_t k = 1; k + 1 < r.v.size(); ++k) {
    if (r.t[k] < kFrom - 1e-12) continue;
    miss += (executed(k) - r.a0[k - 1]).squaredNorm();
    planned += r.a0[k - 1].squaredNorm();
  }
  return std::sqrt(miss / planned);
}

TEST(DelayCompensation, PlantExecutesTheAccelerationPlannedOneUpdateEarlier) {
  const LoopLog r = run_swingup();
  const Model& model = *r.model;
  ASSERT_EQ(r.v.size(), static_cast<size_t>(std::lround(kDuration / r.dt)));
  double speed = 0;
  for (const VecX<double>& v : r.v) speed = std::max(speed, v.cwiseAbs().maxCoeff());
  ASSERT_GE(speed, 3.0) << "the arm must move for the compensation to matter";

  const double miss = relative_miss(r, [&](size_t k) -> VecX<double> { return (r.v[k + 1] - r.v[k]) / r.dt; });
  // the test's power, on the same states: the plant's acceleration had the torque of the update
  // at t_{k−1} been ID at the measured state (q_{k−1}, v_{k−1}) instead of the predicted one
  Data data(model);
  const double uncompensated = relative_miss(r, [&](size_t k) -> VecX<double> {
    const VecX<double> tau = rnea(model, data, r.q[k - 1], r.v[k - 1], r.a0[k - 1]);
    return aba(model, data, r.q[k], r.v[k], tau);
  });
  std::printf("[ measured ] executed vs planned acceleration from t = %g s, relative RMS: %.3g (bound %g); "
              "%.3g with the torques evaluated at the measured states\n",
              kFrom, miss, kMiss, uncompensated);
  EXPECT_LE(miss, kMiss) << "the plant does not execute the planned accelerations: is the torque evaluated at "
                            "the state predicted for its application (eqs. 27–28)?";
  EXPECT_GE(uncompensated, 3 * kMiss) << "without the prediction the miss must be well beyond the bound";
}

}  // namespace
}  // namespace idmpc
