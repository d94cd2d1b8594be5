// MuJoCo's friction loss against the horizon's smooth friction f·tanh(v/ε) (formulations.md §Passive forces), on the
// shipped FR3 as published. MuJoCo solves friction loss as a soft constraint: with no other force
// on the joint it acts as a saturated viscous law, |τ| = min(f, k·|v|), whose slope k grows with
// the joint's inertia (its reference acceleration has the constraint's time constant). The test
// prints both over a range of speeds (`build/tests/friction_loss_test` shows the table that
// docs/passive_forces.md quotes) and checks where they agree.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "idmpc/dynamics/rnea.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc {
namespace {

// the joint torque MuJoCo's friction-loss rows give joint j moving alone at speed v from the home
// pose, with nothing else acting (contacts, limits, gravity, actuators and passive forces off)
double mujoco_friction(mjModel* m, mjData* d, int key, int j, double v) {
  mju_copy(d->qpos, m->key_qpos + static_cast<std::size_t>(key) * m->nq, m->nq);
  mju_zero(d->qvel, m->nv);
  d->qvel[j] = v;
  mj_forward(m, d);
  return -d->qfrc_constraint[j];
}

TEST(FrictionLoss, SmoothModelMatchesMujocosSlidingFrictionAndIsSaidWhereItDoesNot) {
  const std::string path = std::string(IDMPC_SOURCE_DIR) + "/mjcf/fr3.xml";
  // the horizon's friction as `swingup` sets it up for the shipped reach task
  const mj::TaskRun run(load_task(std::string(IDMPC_SOURCE_DIR) + "/mjcf/fr3_reach.json"));
  ASSERT_EQ(run.task().model, path);
  const HorizonSetup& setup = run.horizon();
  const Model& model = run.model();
  const int n = model.n;
  const VecX<double>& q0 = run.q0();
  mj::LoadedModel loaded = mj::load_model_translated(path);
  mjModel* m = loaded.model.get();
  const VecX<double> f = mj::friction_loss(m);
  ASSERT_TRUE((f.array() > 0).all());

  m->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_LIMIT | mjDSBL_GRAVITY | mjDSBL_ACTUATION | mjDSBL_PASSIVE;
  mjData* d = mj_makeData(m);
  const int key = mj_name2id(m, mjOBJ_KEY, "home");
  ASSERT_GE(key, 0);
  // ours: what the friction adds to our RNEA at (q0, v, 0)
  const Model with = with_joint_friction(model, f, setup.friction_velocity);
  Data data_with(with), data_without(model);
  const VecX<double> zero = VecX<double>::Zero(n);
  auto our_friction = [&](int j, double v) {
    VecX<double> vel = zero;
    vel[j] = v;
    return rnea(with, data_with, q0, vel, zero)[j] - rnea(model, data_without, q0, vel, zero)[j];
  };
  std::printf("joint  f [N m]  eps [rad/s]   |tau|/f at v [rad/s] = 0.001 0.01 0.03 0.1 0.3 1 (MuJoCo / tanh)\n");
  for (int j = 0; j < n; ++j) {
    const double eps = setup.friction_velocity[j];
    ASSERT_GT(eps, 0.0);
    std::printf("%5d  %7.3f  %11.3f  ", j, f[j], eps);
    for (double v : {0.001, 0.01, 0.03, 0.1, 0.3, 1.0}) {
      const double mj_tau = mujoco_friction(m, d, key, j, v), ours = our_friction(j, v);
      EXPECT_NEAR(ours, f[j] * std::tanh(v / eps), 1e-12 * f[j]);
      std::printf(" %.2f/%.2f", mj_tau / f[j], ours / f[j]);
      // both oppose the motion and never exceed f
      EXPECT_GT(mj_tau, 0.0);
      EXPECT_LE(mj_tau, f[j] * (1 + 1e-9));
      EXPECT_LE(ours, f[j]);
      // sliding (v ≥ 3ε, where tanh ≥ 0.995): MuJoCo's constraint has saturated at f on this arm,
      // and the two agree to 0.5 % of f
      if (v >= 3 * eps) {
        EXPECT_NEAR(ours, mj_tau, 5e-3 * f[j]) << "joint " << j << " at v = " << v;
      }
      // the reversed speed reverses MuJoCo's torque (to its solver's tolerance), as tanh's
      EXPECT_NEAR(mujoco_friction(m, d, key, j, -v), -mj_tau, 1e-4 * f[j]);
    }
    std::printf("\n");
  }
  mj_deleteData(d);
}

}  // namespace
}  // namespace idmpc
