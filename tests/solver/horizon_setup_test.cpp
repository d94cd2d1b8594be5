// setup_horizon's automatic choices (horizon_setup.hpp), each recomputed here from its rule:
// the friction smoothing velocity ε, the torque weight R, and the implicit damping step of the
// horizon model and of the plant model. Each case is set up so that the rule's every term
// matters (asserted, else the case would prove nothing).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/reference.hpp"
#include "idmpc/solver/horizon_setup.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
const std::string kTree = IDMPC_SOURCE_DIR "/mjcf/tree.xml";  // damped joints
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPlantStep = 1e-3;

// a fixed horizon of N steps over Tf, a start and a target off the zero pose, every weight and
// ε "auto", everything else the defaults
ControllerSettings settings_of(const Model& model, double Tf, int N) {
  ControllerSettings s;
  s.cgmres.Tf = Tf;
  s.cgmres.alpha = 0;
  s.N = N;
  s.q_start = VecX<double>::LinSpaced(model.n, 0.3, -0.4);
  s.q_ref = VecX<double>::LinSpaced(model.n, -0.2, 0.5);
  s.plant_step = kPlantStep;
  return s;
}

// max over q_start and q_ref of (M⁻¹)_jj
VecX<double> inverse_inertia(const Model& model, const ControllerSettings& s) {
  Data data(model);
  VecX<double> out = VecX<double>::Zero(model.n);
  for (const VecX<double>& q : {s.q_start, s.q_ref}) {
    out = out.cwiseMax(MatX<double>(crba(model, data, q).inverse()).diagonal());
  }
  return out;
}

// ε_j = max(0.1, Δτ·f_j·(M⁻¹)_jj): the largest ε of a stable explicit step, not below 0.1 rad/s
TEST(HorizonSetup, AutoFrictionVelocityIsTheStepTimesFrictionOverInertia) {
  const Model model = test::load_problem(kArm4).model;
  const int n = model.n;
  ControllerSettings settings = settings_of(model, 1.0, 20);  // Δτ = 0.05 s
  const VecX<double> f = (VecX<double>(n) << 40.0, 20.0, 10.0, 0.01).finished();
  settings.friction_loss = f;
  settings.torque_upper = VecX<double>::Constant(n, 50.0);
  settings.torque_lower = -settings.torque_upper;
  const HorizonSetup s = setup_horizon(model, settings);

  const double dtau = settings.cgmres.Tf / settings.N;
  const VecX<double> minv = inverse_inertia(model, settings);
  int above = 0;
  for (int j = 0; j < n; ++j) {
    const double rule = dtau * f[j] * minv[j];
    above += rule > 2 * kMinFrictionVelocity;
    EXPECT_NEAR(s.friction_velocity[j], std::max(kMinFrictionVelocity, rule), 1e-12 * rule) << "joint " << j;
  }
  ASSERT_GE(above, 2) << "the step rule must decide ε on some joints, else the case proves nothing";
  EXPECT_EQ(s.friction_velocity[n - 1], kMinFrictionVelocity) << "the floor on a joint of little friction";
  // the horizon and the plant model carry the friction with this ε
  EXPECT_EQ(s.horizon_model->friction, f);
  EXPECT_EQ(s.horizon_model->friction_velocity, s.friction_velocity);
  EXPECT_EQ(s.plant_model->friction_velocity, s.friction_velocity);
}

// R_j = max(10/τ_j², Q_q/(m_j²·ω⁴)), τ_j the half-width of [lower, upper] (one-sided: the bound;
// none: 2|holding torque| + 20 rad/s²·M_jj), m_j = 1/(M⁻¹)_jj, ω = 0.35/Δτ
TEST(HorizonSetup, AutoTorqueWeightComesFromTheHalfRangeOrTheHoldingTorque) {
  const Model model = test::load_problem(kArm4).model;
  const int n = model.n;
  ControllerSettings settings = settings_of(model, 0.2, 25);  // Δτ = 8 ms: the step term stays below the range term
  const VecX<double> zero = VecX<double>::Zero(n);
  // two asymmetric ranges, one side only, none
  settings.torque_lower = (VecX<double>(n) << -2.0, -8.0, -kInf, -kInf).finished();
  settings.torque_upper = (VecX<double>(n) << 6.0, 12.0, 3.0, kInf).finished();
  const HorizonSetup s = setup_horizon(model, settings);

  Data data(model);
  const VecX<double> hold = rnea(model, data, settings.q_ref, zero, zero);
  const VecX<double> inertia = crba(model, data, settings.q_ref).diagonal();
  const VecX<double> scale = (VecX<double>(n) << 4.0, 10.0, 3.0, 2 * std::abs(hold[3]) + 20 * inertia[3]).finished();
  const VecX<double> minv = inverse_inertia(model, settings);
  const double omega = 0.35 / (settings.cgmres.Tf / settings.N);
  ASSERT_EQ(s.weights.Qq, VecX<double>::Constant(n, 100.0));
  ASSERT_EQ(s.weights.Qv, VecX<double>::Constant(n, 10.0));
  int range_decides = 0;
  for (int j = 0; j < n; ++j) {
    const double by_range = 10 / (scale[j] * scale[j]);
    const double by_step = 100 * minv[j] * minv[j] / std::pow(omega, 4);
    range_decides += by_range > 4 * by_step;
    EXPECT_NEAR(s.weights.R[j], std::max(by_range, by_step), 1e-12 * by_range) << "joint " << j;
  }
  ASSERT_EQ(range_decides, n) << "the range must decide R on every joint, else the case proves nothing";
}

// the horizon integrates the damping implicitly over its step Δτ when asked (armature + Δτ·D);
// the plant model (torque rule, observer) always over one plant step (armature + δt·D)
TEST(HorizonSetup, ImplicitDampingStepsAreTheHorizonsAndThePlants) {
  const Model model = test::load_problem(kTree).model;
  ASSERT_GT(model.damping.maxCoeff(), 0.0);
  const int n = model.n;
  ControllerSettings settings = settings_of(model, 0.5, 10);  // Δτ = 0.05 s
  settings.torque_upper = VecX<double>::Constant(n, 10.0);
  settings.torque_lower = -settings.torque_upper;
  const double dtau = settings.cgmres.Tf / settings.N;

  settings.implicit_damping = ImplicitDamping::kOn;
  const HorizonSetup on = setup_horizon(model, settings);
  EXPECT_TRUE(on.implicit_damping);
  EXPECT_EQ(on.horizon_model->armature, model.armature + dtau * model.damping);
  EXPECT_EQ(on.plant_model->armature, model.armature + kPlantStep * model.damping);
  EXPECT_EQ(on.horizon_model->damping, model.damping);

  settings.implicit_damping = ImplicitDamping::kOff;
  const HorizonSetup off = setup_horizon(model, settings);
  EXPECT_FALSE(off.implicit_damping);
  EXPECT_EQ(off.horizon_model->armature, model.armature);
  EXPECT_EQ(off.plant_model->armature, model.armature + kPlantStep * model.damping);

  // "auto": implicit exactly when the explicit step is unstable, Δτ·max eig(M⁻¹D) > 1
  settings.implicit_damping = ImplicitDamping::kAuto;
  const HorizonSetup quiet = setup_horizon(model, settings);
  ASSERT_LT(quiet.damping_step_ratio, 1.0);
  EXPECT_FALSE(quiet.implicit_damping);
  const double heavy = 2 / quiet.damping_step_ratio;  // the damping that makes the ratio 2
  std::vector<Link> links;
  for (int i = 0; i < n; ++i) {
    links.push_back(model.link(i));
    links.back().damping *= heavy;
  }
  const Model damped(links, model.gravity, model.name);
  const HorizonSetup loud = setup_horizon(damped, settings);
  EXPECT_NEAR(loud.damping_step_ratio, 2.0, 1e-9);
  EXPECT_TRUE(loud.implicit_damping);
  EXPECT_EQ(loud.horizon_model->armature, damped.armature + dtau * damped.damping);
  // implicit damping needs a fixed horizon (C/GMRES with α = 0; the Riccati solver's always is)
  settings.implicit_damping = ImplicitDamping::kOn;
  settings.cgmres.alpha = 1;
  EXPECT_THROW(setup_horizon(model, settings), std::invalid_argument);
  settings.solver = SolverKind::kRiccati;
  EXPECT_TRUE(setup_horizon(model, settings).implicit_damping);
}

// The open loop's rate λ (horizon_setup.hpp), recomputed from MuJoCo: the largest real part of
// the eigenvalues of [[0, I], [−M⁻¹G, −M⁻¹D]] with M = mj_fullM and G, D central differences of
// mj_inverse's torque at rest in q and in v, over q_start and q_ref: the paper's chain near upright
// (gravity-unstable) and the tree, whose joint damping enters through D. FD under C/GMRES is told at start where λT_f > kIllConditionedGrowth; ID, the Riccati
// solver and a shorter horizon are not.
double mujoco_open_loop_rate(const test::Problem& p, const std::vector<VecX<double>>& qs) {
  mj::Reference ref(p.m.get());
  const int n = p.model.n;
  const VecX<double> zero = VecX<double>::Zero(n);
  const double h = 1e-6;
  double rate = 0;
  for (const VecX<double>& q : qs) {
    MatX<double> G(n, n), D(n, n);
    for (int j = 0; j < n; ++j) {
      const VecX<double> e = VecX<double>::Unit(n, j) * h;
      G.col(j) = (ref.inverse(q + e, zero, zero) - ref.inverse(q - e, zero, zero)) / (2 * h);
      D.col(j) = (ref.inverse(q, e, zero) - ref.inverse(q, -e, zero)) / (2 * h);
    }
    const MatX<double> M = ref.mass_matrix(q);
    MatX<double> A = MatX<double>::Zero(2 * n, 2 * n);
    A.topRightCorner(n, n).setIdentity();
    A.bottomLeftCorner(n, n) = -M.lu().solve(G);
    A.bottomRightCorner(n, n) = -M.lu().solve(D);
    rate = std::max(rate, Eigen::EigenSolver<MatX<double>>(A, false).eigenvalues().real().maxCoeff());
  }
  return rate;
}

TEST(HorizonSetup, OpenLoopRateIsTheFastestGrowthOfTheLinearizedArm) {
  for (const std::string& path : {kArm4, kTree}) {
    SCOPED_TRACE(path);
    const test::Problem p = test::load_problem(path);
    ControllerSettings settings = settings_of(p.model, 1.0, 50);
    settings.formulation = Formulation::kForwardDynamics;
    const HorizonSetup setup = setup_horizon(p.model, settings);
    const double expected = mujoco_open_loop_rate(p, {settings.q_start, settings.q_ref});
    ASSERT_GT(expected, 1.0) << "the case needs an unstable open loop";
    EXPECT_NEAR(setup.open_loop_rate, expected, 1e-6 * expected);
    // said at start for FD's C/GMRES exactly where e^{λT_f} exceeds e^kIllConditionedGrowth
    auto said = [](const HorizonSetup& s) {
      return std::any_of(s.notes.begin(), s.notes.end(),
                         [](const std::string& note) { return note.find("the open loop diverges at") == 0; });
    };
    settings.cgmres.Tf = 1.01 * kIllConditionedGrowth / expected;
    EXPECT_TRUE(said(setup_horizon(p.model, settings)));
    settings.cgmres.Tf = 0.99 * kIllConditionedGrowth / expected;
    EXPECT_FALSE(said(setup_horizon(p.model, settings)));
    settings.cgmres.Tf = 1.01 * kIllConditionedGrowth / expected;
    settings.formulation = Formulation::kInverseDynamics;
    EXPECT_FALSE(said(setup_horizon(p.model, settings)));
    settings.formulation = Formulation::kForwardDynamics;
    settings.solver = SolverKind::kRiccati;
    EXPECT_FALSE(said(setup_horizon(p.model, settings)));
  }
}

// Solver "auto" (horizon_setup.hpp): the Riccati recursion on a fully actuated model whatever its
// open loop (λT_f, λ from MuJoCo, on either side of the line of FD's C/GMRES notice), the same in
// both formulations and said at start; C/GMRES on an under-actuated model, said too; a solver
// named is kept
TEST(HorizonSetup, AutoSolverIsRiccatiOnAFullyActuatedModelAndCgmresOnAnUnderActuatedOne) {
  auto said = [](const HorizonSetup& s, const std::string& what) {
    return std::any_of(s.notes.begin(), s.notes.end(),
                       [&](const std::string& note) { return note.find("solver \"auto\": " + what) == 0; });
  };
  for (const std::string& path : {kArm4, kTree}) {
    SCOPED_TRACE(path);
    const test::Problem p = test::load_problem(path);
    ASSERT_FALSE(p.model.under_actuated());
    ControllerSettings settings = settings_of(p.model, 1.0, 50);
    const double lambda = mujoco_open_loop_rate(p, {settings.q_start, settings.q_ref});
    ASSERT_GT(lambda, 1.0) << "the case needs an unstable open loop";
    for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      settings.formulation = f;
      for (const double growth : {0.5, 0.99, 1.01, 2.0}) {
        SCOPED_TRACE(growth);
        settings.solver = SolverKind::kAuto;
        settings.cgmres.Tf = growth * kIllConditionedGrowth / lambda;
        const HorizonSetup setup = setup_horizon(p.model, settings);
        EXPECT_EQ(setup.solver, SolverKind::kRiccati);
        EXPECT_TRUE(said(setup, "Riccati in both formulations"));
        for (const SolverKind named : {SolverKind::kCgmres, SolverKind::kRiccati}) {
          settings.solver = named;
          const HorizonSetup kept = setup_horizon(p.model, settings);
          EXPECT_EQ(kept.solver, named);
          EXPECT_FALSE(said(kept, "")) << "a solver named is not chosen";
        }
      }
    }
  }
  // under-actuated: the cart-pole's upright target is unstable by construction, C/GMRES kept
  const test::Problem cartpole = test::load_problem(IDMPC_SOURCE_DIR "/mjcf/cartpole.xml");
  ASSERT_TRUE(cartpole.model.under_actuated());
  ControllerSettings s = settings_of(cartpole.model, 2.0, 50);
  s.q_ref = VecX<double>::Zero(cartpole.model.n);
  for (const Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    s.formulation = f;
    s.solver = SolverKind::kAuto;
    const HorizonSetup setup = setup_horizon(cartpole.model, s);
    EXPECT_EQ(setup.solver, SolverKind::kCgmres);
    EXPECT_TRUE(said(setup, "C/GMRES in both formulations"));
    EXPECT_FALSE(said(setup, "Riccati"));
  }
}

// Settings the rules cannot use are refused, naming the setting; without friction loss given the
// model keeps its own friction terms
TEST(HorizonSetup, RefusesSettingsOfTheWrongSizeAndKeepsTheModelsFriction) {
  const Model model = test::load_problem(kArm4).model;
  const int n = model.n;
  ControllerSettings settings = settings_of(model, 0.5, 10);
  for (auto [field, name] : {std::pair{&ControllerSettings::q_start, "q_start"},
                             std::pair{&ControllerSettings::friction_loss, "friction_loss"},
                             std::pair{&ControllerSettings::friction_velocity, "friction_velocity"}}) {
    ControllerSettings bad = settings;
    bad.*field = VecX<double>::Ones(n + 1);
    try {
      setup_horizon(model, bad);
      ADD_FAILURE() << name << " of the wrong size accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  ControllerSettings bad = settings;
  bad.weights.R = VecX<double>::Ones(n - 1);
  EXPECT_THROW(setup_horizon(model, bad), std::invalid_argument);
  bad = settings;
  bad.friction_loss = VecX<double>::Constant(n, -1.0);
  EXPECT_THROW(setup_horizon(model, bad), std::invalid_argument);

  const Model rough = with_joint_friction(model, VecX<double>::Constant(n, 2.0), VecX<double>::Constant(n, 0.3));
  const HorizonSetup kept = setup_horizon(rough, settings);
  EXPECT_EQ(kept.horizon_model->friction, rough.friction);
  EXPECT_EQ(kept.plant_model->friction_velocity, rough.friction_velocity);
}

}  // namespace
}  // namespace idmpc

namespace idmpc {
namespace {

// an under-actuated model's terminal cost: P solves the Riccati equation of the horizon step
// linearized at the target, recomputed here from central differences of ABA (not the analytic
// derivatives the setup uses); none on a fully actuated model or off an equilibrium
TEST(HorizonSetup, UnderActuatedTerminalCostIsTheLqrValueOfTheTarget) {
  const test::Problem p = test::load_problem(IDMPC_SOURCE_DIR "/mjcf/cartpole.xml");
  const Model& model = p.model;
  ASSERT_TRUE(model.under_actuated());
  const int n = model.n;
  ControllerSettings s = settings_of(model, 0.5, 25);
  s.q_ref = VecX<double>::Zero(n);  // upright: an equilibrium of the passive hinge
  const HorizonSetup setup = setup_horizon(model, s);
  const MatX<double>& P = setup.terminal_weight;
  ASSERT_EQ(P.rows(), 2 * n);
  ASSERT_EQ(P.cols(), 2 * n);
  EXPECT_TRUE(std::any_of(setup.notes.begin(), setup.notes.end(),
                          [](const std::string& s) { return s.find("LQR value") != std::string::npos; }));

  // the linearized Euler step of the horizon model, by central differences
  const double dtau = 0.5 / 25;
  const Model& hm = *setup.horizon_model;
  Data data(hm);
  const VecX<double> zero = VecX<double>::Zero(n);
  const VecX<double> tau = rnea(hm, data, s.q_ref, zero, zero);
  auto f = [&](const VecX<double>& x, double u) {
    VecX<double> t = tau;
    t[model.actuated_joints[0]] += u;
    const VecX<double> a = aba(hm, data, x.head(n), x.tail(n), t);
    VecX<double> next(2 * n);
    next << x.head(n) + dtau * x.tail(n), x.tail(n) + dtau * a;
    return next;
  };
  const double e = 1e-6;
  MatX<double> A(2 * n, 2 * n), B(2 * n, 1);
  const VecX<double> x0 = VecX<double>::Zero(2 * n);
  for (int c = 0; c < 2 * n; ++c) {
    VecX<double> dx = VecX<double>::Zero(2 * n);
    dx[c] = e;
    A.col(c) = (f(x0 + dx, 0) - f(x0 - dx, 0)) / (2 * e);
  }
  B.col(0) = (f(x0, e) - f(x0, -e)) / (2 * e);
  VecX<double> qd(2 * n);
  qd << setup.weights.Qq, setup.weights.Qv;
  const MatX<double> Q = dtau * MatX<double>(qd.asDiagonal());
  const double R = dtau * setup.weights.R[model.actuated_joints[0]];
  const MatX<double> PB = P * B;
  const MatX<double> residual =
      Q + A.transpose() * P * A - A.transpose() * PB * (1.0 / (R + (B.transpose() * PB)(0, 0))) * PB.transpose() * A - P;
  EXPECT_LE(residual.cwiseAbs().maxCoeff(), 1e-6 * P.cwiseAbs().maxCoeff()) << residual;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX<double>>(P).eigenvalues().minCoeff(), 0);

  // a start near the target keeps it; a swing-up's start (the pole hanging) does not
  s.q_start = VecX<double>::Zero(n);
  s.q_start[1] = 0.7;
  EXPECT_EQ(setup_horizon(model, s).terminal_weight.size(), 4 * n * n);
  s.q_start[1] = 3.14;
  const HorizonSetup swing = setup_horizon(model, s);
  EXPECT_EQ(swing.terminal_weight.size(), 0);
  EXPECT_TRUE(std::any_of(swing.notes.begin(), swing.notes.end(),
                          [](const std::string& s) { return s.find("linearization's reach") != std::string::npos; }));
  s.q_start.resize(0);

  // off an equilibrium (the pole tilted: the hinge would need a torque) and fully actuated: none
  s.q_ref[1] = 0.3;
  const HorizonSetup tilted = setup_horizon(model, s);
  EXPECT_EQ(tilted.terminal_weight.size(), 0);
  EXPECT_TRUE(std::any_of(tilted.notes.begin(), tilted.notes.end(),
                          [](const std::string& s) { return s.find("not an equilibrium") != std::string::npos; }));
  const test::Problem arm = test::load_problem(kArm4);
  EXPECT_EQ(setup_horizon(arm.model, settings_of(arm.model, 0.5, 25)).terminal_weight.size(), 0);
}

TEST(HorizonSetup, DareSolutionOfAScalarSystemIsTheClosedForm) {
  // x⁺ = a x + b u, cost q x² + r u²: P = q + a²P − a²b²P²/(r + b²P), the positive root
  const double a = 1.3, b = 0.5, q = 2.0, r = 0.7;
  const MatX<double> P = solve_dare(MatX<double>::Constant(1, 1, a), MatX<double>::Constant(1, 1, b),
                                    MatX<double>::Constant(1, 1, q), MatX<double>::Constant(1, 1, r));
  ASSERT_EQ(P.size(), 1);
  // b²P² + (r − a²r − qb²)P − qr = 0
  const double A2 = b * b, B1 = r - a * a * r - q * b * b, C0 = -q * r;
  const double expected = (-B1 + std::sqrt(B1 * B1 - 4 * A2 * C0)) / (2 * A2);
  EXPECT_NEAR(P(0, 0), expected, 1e-12 * expected);
  // not stabilizable: an unstable mode no input reaches
  EXPECT_EQ(solve_dare(MatX<double>::Constant(1, 1, a), MatX<double>::Zero(1, 1), MatX<double>::Constant(1, 1, q),
                       MatX<double>::Constant(1, 1, r))
                .size(),
            0);
}

}  // namespace
}  // namespace idmpc
