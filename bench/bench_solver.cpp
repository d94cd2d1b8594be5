// Solver layer: the cost of one C/GMRES update of the four controllers (FD/ID × matrix/adjoint)
// on the paper's grids, timed on states of a real closed-loop swing-up and warm-started exactly
// as in the loop.
//
// Fixture (outside timing, once per case): the swing-up of mjcf/paper_swingup.json (q0 = (−π, 0, …), q_ref = 0,
// paper weights) runs in closed loop with the MuJoCo plant and the case's controller for 0.3 s
// (fewer steps, at least 20, where that would take over ~1.5 s of wall time: counter states),
// recording the measured (t, q, v) and the solution U of every successful update. The
// timed loop then replays those measurements through a copy of the solver taken right after its
// zero-horizon initialization, so each timed update is the very computation the loop made; at the
// end of the record the copy is restored (one copy per cycle, amortized). A run that diverged is
// replayed up to its last successful update and reported with counter diverged = 1; an ID run
// that diverges with Q_a = 0 is redone with the paper's fallback Q_a = 1e-4 (counter Qa).
//
// Cases: BM_Update/<fd|id>_<matrix|adjoint>/n:<n>/N:<N>/kmax:<kmax>, the union of
//   Tables 1–2 (arm4: N ∈ {10,15,25,50} × kmax ∈ {3,5,10}),
//   Table 3 and the size scaling (n ∈ {4,8,16,24,32,48,64}, N = 25, kmax = 10),
//   the horizon scaling (n ∈ {4,16}, N ∈ {10,15,25,50,75,100}, kmax = 10);
// BM_Update/<fd|id>_<matrix|adjoint>_multiple/…: the same controllers under multiple shooting
//   (formulations.md §Multiple shooting), on Tables 1–3 and n ≤ 32;
// BM_Residual/<controller>/n:<n>/N:25 times one F evaluation on the same states and solutions;
// BM_Update/<controller>_exact/…: with exact products (formulations.md §Exact products), N = 25, kmax = 10, n ≤ 16;
// BM_Product/<controller>_exact/n:<n>/N:25 times one exact product with its residual;
// BM_StageVectorOps/n:<n> times the vector work of one ID stage without its dynamics calls.
// BM_UnderActuated/<fd|id>/cartpole/kmax:<kmax>: one C/GMRES update (adjoint, stages in lanes)
//   on the cart-pole swing-up of mjcf/cartpole_swingup.json (formulations.md §Under-actuation:
//   FD's input is the cart's force, ID's the accelerations with the hinge's torque constrained),
//   replayed on the states of its own 0.3 s closed loop as above.
// BM_Riccati/<fd|id>/n:<n>/N:<N>: one update of the Riccati solver (one real-time Gauss–Newton
//   iteration: docs/solvers.md), replayed on the states of its own closed-loop swing-up as above,
//   on Table 3's sizes and the horizon scaling (n ∈ {4,16}, N ∈ {10 … 100}).
// BM_UnderActuatedRiccati/<fd|id>/<acrobot|pendubot|cartpole>: one Riccati update on the shipped
//   swing-up task of that model (mjcf/<model>_swingup.json under the Riccati solver: FD's input the
//   actuator's torque, ID's the accelerations with the passive torque eliminated), replayed on
//   the states of its own 0.3 s closed loop.

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "bench_support.hpp"
#include "idmpc/experiment/data_dir.hpp"
#include "idmpc/experiment/task.hpp"
#include "idmpc/mujoco/closed_loop.hpp"
#include "idmpc/mujoco/task_run.hpp"
#include "idmpc/solver/shooting.hpp"
#include "idmpc/solver/controller.hpp"
#include "idmpc/solver/riccati.hpp"

namespace idmpc::bench {
namespace {

// recorded swing-up: simulated time, and a cap on the fixture's wall time for the expensive cases
constexpr double kRecordSeconds = 0.3;
constexpr double kRecordBudgetSeconds = 1.5;
constexpr int kMinRecordedSteps = 20;

struct Controller {
  Formulation formulation;
  DerivativeMode mode;
  bool simd_stages = true;  ///< horizon stages in SIMD lanes where independent (the default)
  ShootingScheme shooting = ShootingScheme::kSingle;
  Products products = Products::kDifference;
  std::string name() const {
    return to_string(formulation) + "_" + to_string(mode) + (simd_stages ? "" : "_scalar") +
           (shooting == ShootingScheme::kSingle ? "" : "_" + to_string(shooting)) +
           (products == Products::kDifference ? "" : "_" + to_string(products));
  }
};

const Controller kControllers[] = {
    {Formulation::kForwardDynamics, DerivativeMode::kMatrix},
    {Formulation::kForwardDynamics, DerivativeMode::kAdjoint},
    {Formulation::kInverseDynamics, DerivativeMode::kMatrix},
    {Formulation::kInverseDynamics, DerivativeMode::kAdjoint},
    // what the SIMD stage lanes buy: the same controller stage by stage (N = 25, kmax = 10 only);
    // in matrix mode that is the paper's arithmetic (Pinocchio's derivatives, stage by stage)
    {Formulation::kForwardDynamics, DerivativeMode::kMatrix, false},
    {Formulation::kInverseDynamics, DerivativeMode::kMatrix, false},
    {Formulation::kInverseDynamics, DerivativeMode::kAdjoint, false},
    // multiple shooting (Tables 1–3 and n ≤ 32 only)
    {Formulation::kForwardDynamics, DerivativeMode::kMatrix, true, ShootingScheme::kMultiple},
    {Formulation::kForwardDynamics, DerivativeMode::kAdjoint, true, ShootingScheme::kMultiple},
    {Formulation::kInverseDynamics, DerivativeMode::kMatrix, true, ShootingScheme::kMultiple},
    {Formulation::kInverseDynamics, DerivativeMode::kAdjoint, true, ShootingScheme::kMultiple},
    // exact products in dual numbers, stage by stage (formulations.md §Exact products; N = 25, kmax = 10, n ≤ 16)
    {Formulation::kForwardDynamics, DerivativeMode::kMatrix, true, ShootingScheme::kSingle, Products::kExact},
    {Formulation::kForwardDynamics, DerivativeMode::kAdjoint, true, ShootingScheme::kSingle, Products::kExact},
    {Formulation::kInverseDynamics, DerivativeMode::kMatrix, true, ShootingScheme::kSingle, Products::kExact},
    {Formulation::kInverseDynamics, DerivativeMode::kAdjoint, true, ShootingScheme::kSingle, Products::kExact},
};

struct Case {
  Controller controller;
  int n, N, kmax;
  auto key() const {
    return std::make_tuple(static_cast<int>(controller.formulation), static_cast<int>(controller.mode),
                           controller.simd_stages, static_cast<int>(controller.shooting),
                           static_cast<int>(controller.products), n, N, kmax);
  }
};

// the paper's task (mjcf/paper_swingup.json) on an n-joint model, with Q_a and kmax set
ResolvedTask paper_setup(int n, double Qa, int kmax) {
  ResolvedTask r = resolve(paper_task(), n);
  r.controller.weights.Qa.setConstant(Qa);
  r.controller.cgmres.kmax = kmax;
  return r;
}

// one controller on one model, the swing-up it produced, and the solver replaying it
// a recorded closed loop's measurements (t, q, v of a fixture): one step appended while it
// runs, then only those of its successful updates kept
template <typename Fixture> void record_step(Fixture& f, const mj::StepRecord& r) {
  f.t.push_back(r.t);
  f.q.push_back(r.q);
  f.v.push_back(r.v);
}
template <typename Fixture> void keep_updates(Fixture& f, const mj::RunResult& result) {
  const size_t ok = result.update_ms.size();
  f.t.resize(ok);
  f.q.resize(ok);
  f.v.resize(ok);
}

struct SolverFixture {
  decltype(std::declval<Case>().key()) key;
  const BenchModel* bm = nullptr;
  double Qa = 0;
  std::unique_ptr<Shooting> ocp;
  std::unique_ptr<Cgmres> start;  // right after the zero-horizon initialization at t = 0
  std::optional<Cgmres> solver;   // replays the record from `start`
  std::vector<double> t;
  std::vector<VecX<double>> q, v, U;  // measured state and solution after each update
  bool diverged = false;
  double diverged_at = std::nan("");
  size_t next = 0;
  VecX<double> F;
};

// runs the closed loop and records it; returns whether the run diverged
bool record_swingup(SolverFixture& f, const Case& c) {
  const int n = c.n;
  const ResolvedTask paper = paper_setup(n, f.Qa, c.kmax);
  const VecX<double>& q0 = paper.q0;
  const VecX<double> v0 = VecX<double>::Zero(n);
  f.ocp = std::make_unique<Shooting>(f.bm->model(), c.controller.formulation, c.controller.mode,
                                           paper.controller.weights, paper.controller.q_ref, c.N);
  f.ocp->set_stage_batching(c.controller.simd_stages);
  CgmresSettings settings = paper.controller.cgmres;
  settings.shooting = c.controller.shooting;
  settings.products = c.controller.products;
  f.start = std::make_unique<Cgmres>(*f.ocp, settings);
  f.start->initialize(0.0, q0, v0);

  // probe the update cost to keep the recording within its wall-time budget
  double duration = kRecordSeconds;
  {
    Cgmres probe(*f.start);
    const auto t0 = std::chrono::steady_clock::now();
    constexpr int kProbe = 2;
    for (int k = 0; k < kProbe; ++k) probe.update(k * settings.dt, q0, v0);
    const double per_update =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / kProbe;
    const double steps = std::floor(kRecordBudgetSeconds / std::max(per_update, 1e-9));
    duration = std::min(kRecordSeconds, std::max<double>(kMinRecordedSteps, steps) * settings.dt);
  }

  // the swing-up in closed loop, recording each measurement and the solution it produced
  idmpc::Controller controller(f.ocp->problem(), settings);
  mj::Plant plant(f.bm->m.get(), f.bm->imported.actuation);
  mj::ClosedLoopSettings loop;
  loop.duration = duration;
  loop.q0 = q0;
  loop.v0 = v0;
  loop.phase_timing = false;
  f.t.clear();
  f.q.clear();
  f.v.clear();
  f.U.clear();
  const mj::RunResult result =
      mj::run_closed_loop(plant, controller, loop, [&](const mj::StepRecord& r) {
        record_step(f, r);
        f.U.push_back(controller.cgmres().solution());
      });
  keep_updates(f, result);
  f.U.resize(f.t.size());
  f.diverged = result.diverged;
  f.diverged_at = result.diverged_at;
  return result.diverged;
}

SolverFixture& fixture(const Case& c) {
  static std::unique_ptr<SolverFixture> current;  // one case at a time: cases run in order
  if (current && current->key == c.key()) return *current;
  current.reset();
  auto f = std::make_unique<SolverFixture>();
  f->key = c.key();
  f->bm = &bench_model(c.n);
  f->Qa = 0;
  if (record_swingup(*f, c) && c.controller.formulation == Formulation::kInverseDynamics &&
      paper_task().Qa_fallback > 0) {
    f->Qa = paper_task().Qa_fallback;
    record_swingup(*f, c);
  }
  f->F = VecX<double>::Zero(f->ocp->dim());
  if (!f->t.empty()) f->solver.emplace(*f->start);
  current = std::move(f);
  return *current;
}

void common_counters(benchmark::State& state, const Case& c, const SolverFixture& f) {
  state.counters["n"] = c.n;
  state.counters["N"] = c.N;
  state.counters["kmax"] = c.kmax;
  state.counters["diverged"] = f.diverged ? 1 : 0;
  state.counters["diverged_at"] = f.diverged ? f.diverged_at : -1;
  state.counters["Qa"] = f.Qa;
  state.counters["states"] = static_cast<double>(f.t.size());
}

// the next recorded update of fixture f (its measured t, q, v) by its replaying solver; at the end
// of the record, back to the solver that started it. Returns the update's F evaluations.
template <typename Fixture> int replay_update(Fixture& f) {
  if (f.next == f.t.size()) {
    f.solver.emplace(*f.start);
    f.next = 0;
  }
  const size_t k = f.next++;
  const bool ok = f.solver->update(f.t[k], f.q[k], f.v[k]);
  benchmark::DoNotOptimize(ok);
  benchmark::DoNotOptimize(f.solver->solution().data());
  return f.solver->evaluations();
}

// one C/GMRES update, cycling through the recorded measurements
void BM_Update(benchmark::State& state, Case c) {
  SolverFixture& f = fixture(c);
  if (f.t.empty()) {
    state.SkipWithError("the swing-up diverged before its first update");
    return;
  }
  long evaluations = 0;
  for (auto _ : state) evaluations += replay_update(f);
  common_counters(state, c, f);
  const double iterations = static_cast<double>(state.iterations());
  state.counters["evals"] = evaluations / iterations;
  // time per F evaluation [us]: a rate inverted
  state.counters["us_per_eval"] =
      benchmark::Counter(1e-6 * evaluations, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// one F evaluation alone, on the recorded states and solutions
void BM_Residual(benchmark::State& state, Case c) {
  SolverFixture& f = fixture(c);
  if (f.t.empty()) {
    state.SkipWithError("the swing-up diverged before its first update");
    return;
  }
  size_t k = 0;
  for (auto _ : state) {
    if (k == f.t.size()) k = 0;
    f.ocp->residual(f.U[k], f.q[k], f.v[k], f.start->horizon(f.t[k]), f.F);
    benchmark::DoNotOptimize(f.F.data());
    benchmark::ClobberMemory();
    ++k;
  }
  common_counters(state, c, f);
}

// one exact product (∂F/∂U)·W with the residual, in dual numbers, on the recorded states and
// solutions (W: the solution's direction, any fixed vector of its size does): beside
// BM_Residual, the cost of an exact product against a difference product's one evaluation
void BM_Product(benchmark::State& state, Case c) {
  SolverFixture& f = fixture(c);
  if (f.t.empty()) {
    state.SkipWithError("the swing-up diverged before its first update");
    return;
  }
  const VecX<double> W = VecX<double>::Ones(f.ocp->dim());
  VecX<double> dF = VecX<double>::Zero(f.ocp->dim());
  size_t k = 0;
  for (auto _ : state) {
    if (k == f.t.size()) k = 0;
    f.ocp->residual_and_product(f.U[k], W, f.q[k], f.v[k], f.start->horizon(f.t[k]), f.F, dF);
    benchmark::DoNotOptimize(dF.data());
    benchmark::ClobberMemory();
    ++k;
  }
  common_counters(state, c, f);
}

// the vector work of the ID residual's stages (Euler rollout, w = R u, costates, F_i) with the
// RNEA and adjoint calls replaced by their stored outputs: with BM_RneaVjp it prices one stage
void BM_StageVectorOps(benchmark::State& state, int n) {
  constexpr int N = 25;
  const double dtau = 0.5 / N;
  const OcpWeights w8 = paper_setup(n, 0.0, 10).controller.weights;
  const VecX<double> q_ref = VecX<double>::Zero(n);
  VecX<double> U = VecX<double>::Random(N * n), F = VecX<double>::Zero(N * n);
  MatX<double> q = MatX<double>::Random(n, N + 1), v = MatX<double>::Random(n, N + 1);
  MatX<double> a = MatX<double>::Zero(n, N), u = MatX<double>::Zero(n, N);
  const VecX<double> tau = VecX<double>::Random(n), g_q = VecX<double>::Random(n),
                     g_v = VecX<double>::Random(n), g_a = VecX<double>::Random(n);
  VecX<double> lmd(n), gmm(n), lmd_next(n), gmm_next(n), gq(n), gv(n), w(n);
  for (auto _ : state) {
    for (int i = 0; i < N; ++i) {
      a.col(i) = U.segment(i * n, n);
      u.col(i) = tau;
      q.col(i + 1) = q.col(i) + dtau * v.col(i);
      v.col(i + 1) = v.col(i) + dtau * a.col(i);
    }
    lmd_next = w8.Qq.cwiseProduct(q.col(N) - q_ref);
    gmm_next = w8.Qv.cwiseProduct(v.col(N));
    for (int i = N - 1; i >= 0; --i) {
      w = w8.R.cwiseProduct(u.col(i));
      benchmark::DoNotOptimize(w.data());
      gq = g_q;
      gv = g_v;
      F.segment(i * n, n) = gmm_next + w8.Qa.cwiseProduct(a.col(i)) + g_a;
      lmd = lmd_next + dtau * (w8.Qq.cwiseProduct(q.col(i) - q_ref) + gq);
      gmm = gmm_next + dtau * (w8.Qv.cwiseProduct(v.col(i)) + lmd_next + gv);
      lmd_next.swap(lmd);
      gmm_next.swap(gmm);
    }
    benchmark::DoNotOptimize(F.data());
    benchmark::ClobberMemory();
  }
  state.counters["n"] = n;
  state.counters["N"] = N;
  // per stage [ns]
  state.counters["ns_per_stage"] = benchmark::Counter(
      1e-9 * N, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// the Riccati solver on one model and horizon: its swing-up, and a copy of its start to replay from
struct RiccatiFixture {
  std::tuple<int, int, int> key;
  std::optional<RiccatiSolver> start, solver;
  std::vector<double> t;
  std::vector<VecX<double>> q, v;
  size_t next = 0;
  bool diverged = false;
};

RiccatiFixture& riccati_fixture(Formulation f, int n, int N) {
  static std::unique_ptr<RiccatiFixture> current;  // one case at a time
  const auto key = std::make_tuple(static_cast<int>(f), n, N);
  if (current && current->key == key) return *current;
  current = std::make_unique<RiccatiFixture>();
  RiccatiFixture& fx = *current;
  fx.key = key;
  const BenchModel& bm = bench_model(n);
  const ResolvedTask paper = paper_setup(n, 0.0, 10);
  const VecX<double> v0 = VecX<double>::Zero(n);
  const OcpProblem problem(bm.model(), f, DerivativeMode::kMatrix, paper.controller.weights, paper.controller.q_ref, N);
  RiccatiSolver solver(problem, paper.controller.cgmres.Tf, paper.controller.cgmres.dt, RiccatiSettings{});
  solver.initialize(0.0, paper.q0, v0);
  fx.start.emplace(solver);
  idmpc::Controller controller(std::make_unique<RiccatiSolver>(problem, paper.controller.cgmres.Tf, paper.controller.cgmres.dt,
                                                               RiccatiSettings{}));
  mj::Plant plant(bm.m.get(), bm.imported.actuation);
  mj::ClosedLoopSettings loop;
  loop.duration = kRecordSeconds;
  loop.q0 = paper.q0;
  loop.v0 = v0;
  loop.phase_timing = false;
  const mj::RunResult result =
      mj::run_closed_loop(plant, controller, loop, [&](const mj::StepRecord& r) { record_step(fx, r); });
  keep_updates(fx, result);
  fx.diverged = result.diverged;
  fx.solver = fx.start;
  return fx;
}

// the cart-pole swing-up under one formulation and kmax: its recorded closed loop and the solver
// replaying it from right after its start
struct UnderActuatedFixture {
  std::pair<int, int> key{-1, -1};
  std::unique_ptr<mj::TaskRun> run;
  std::unique_ptr<Cgmres> start;
  std::optional<Cgmres> solver;
  std::vector<double> t;
  std::vector<VecX<double>> q, v;
  size_t next = 0;
};

void BM_UnderActuated(benchmark::State& state, Formulation formulation, int kmax) {
  static std::unique_ptr<UnderActuatedFixture> current;  // one case at a time: cases run in order
  const std::pair<int, int> key{static_cast<int>(formulation), kmax};
  if (!current || current->key != key) {
    current.reset();
    current = std::make_unique<UnderActuatedFixture>();
    UnderActuatedFixture& f = *current;
    f.key = key;
    Task task = load_task(shipped_mjcf_path("cartpole_swingup.json"));
    task.solver = "cgmres";  // the C/GMRES update is what is timed
    task.formulation = to_string(formulation);
    task.kmax = kmax;
    task.duration = kRecordSeconds;
    f.run = std::make_unique<mj::TaskRun>(task);
    mj::ClosedLoopSettings loop = f.run->loop_settings();
    loop.phase_timing = false;
    keep_updates(f, f.run->run(loop, [&](const mj::StepRecord& r) { record_step(f, r); }));
    f.run->controller().initialize(f.run->q0(), VecX<double>::Zero(f.run->n()));
    f.start = std::make_unique<Cgmres>(f.run->controller().cgmres());
    f.solver.emplace(*f.start);
  }
  UnderActuatedFixture& f = *current;
  if (f.t.empty()) {
    state.SkipWithError("the swing-up diverged before its first update");
    return;
  }
  for (auto _ : state) replay_update(f);
  state.counters["kmax"] = kmax;
  state.counters["unknowns_per_stage"] = f.run->controller().problem().stage_dim();
  state.counters["states"] = static_cast<double>(f.t.size());
}

// the next recorded update of a Riccati fixture; returns its evaluations
int replay_riccati(RiccatiFixture& fx) {
  if (fx.next == fx.t.size()) {
    fx.solver = fx.start;
    fx.next = 0;
  }
  const size_t k = fx.next++;
  const bool ok = fx.solver->update(fx.t[k], fx.q[k], fx.v[k]);
  benchmark::DoNotOptimize(ok);
  benchmark::DoNotOptimize(fx.solver->first_input().data());
  return fx.solver->evaluations();
}

void BM_Riccati(benchmark::State& state, Formulation f, int n, int N) {
  RiccatiFixture& fx = riccati_fixture(f, n, N);
  if (fx.t.empty()) {
    state.SkipWithError("the swing-up diverged before its first update");
    return;
  }
  long evaluations = 0;
  for (auto _ : state) evaluations += replay_riccati(fx);
  state.counters["n"] = n;
  state.counters["N"] = N;
  state.counters["diverged"] = fx.diverged ? 1 : 0;
  state.counters["states"] = static_cast<double>(fx.t.size());
  state.counters["evals"] = evaluations / static_cast<double>(state.iterations());
  // per stage [us]
  state.counters["us_per_stage"] = benchmark::Counter(
      1e-6 * N, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

const char* const kUnderActuatedTasks[] = {"acrobot", "pendubot", "cartpole"};

void BM_UnderActuatedRiccati(benchmark::State& state, Formulation formulation, int task_index) {
  static std::unique_ptr<RiccatiFixture> current;  // one case at a time
  const auto key = std::make_tuple(static_cast<int>(formulation), task_index, -1);
  if (!current || current->key != key) {
    current = std::make_unique<RiccatiFixture>();
    RiccatiFixture& fx = *current;
    fx.key = key;
    Task task = load_task(shipped_mjcf_path(std::string(kUnderActuatedTasks[task_index]) + "_swingup.json"));
    task.solver = "riccati";
    task.formulation = to_string(formulation);
    task.duration = kRecordSeconds;
    mj::TaskRun run(task);
    mj::ClosedLoopSettings loop = run.loop_settings();
    loop.phase_timing = false;
    const mj::RunResult result = run.run(loop, [&](const mj::StepRecord& r) { record_step(fx, r); });
    keep_updates(fx, result);
    fx.diverged = result.diverged;
    run.controller().initialize(run.q0(), VecX<double>::Zero(run.n()));
    fx.start.emplace(dynamic_cast<const RiccatiSolver&>(run.controller().solver()));
    fx.solver = fx.start;
  }
  RiccatiFixture& fx = *current;
  if (fx.t.empty()) {
    state.SkipWithError("the swing-up diverged before its first update");
    return;
  }
  for (auto _ : state) replay_riccati(fx);
  state.counters["inputs"] = fx.solver->problem().input_dim();
  state.counters["states"] = static_cast<double>(fx.t.size());
}

void register_all() {
  // the union of the grids, in order, each case once
  std::vector<std::tuple<int, int, int>> cases;  // (n, N, kmax)
  std::set<std::tuple<int, int, int>> seen;
  auto add = [&](int n, int N, int kmax) {
    if (seen.insert({n, N, kmax}).second) cases.emplace_back(n, N, kmax);
  };
  std::set<std::tuple<int, int, int>> paper;  // Tables 1–3 and n ≤ 32 at N = 25, kmax = 10
  for (const PaperCell& p : load_paper_tables().cells) {
    add(p.n, p.N, p.kmax);  // Tables 1–3
    paper.insert({p.n, p.N, p.kmax});
  }
  for (int n : {4, 8, 16, 24, 32}) paper.insert({n, 25, 10});
  for (int n : {4, 8, 16, 24, 32, 48, 64}) add(n, 25, 10);  // Table 3 and size scaling
  for (int n : {4, 16}) {
    for (int N : {10, 15, 25, 50, 75, 100}) add(n, N, 10);  // horizon scaling
  }

  for (const auto& [n, N, kmax] : cases) {
    for (const Controller& ctrl : kControllers) {
      if (!ctrl.simd_stages && !(N == 25 && kmax == 10)) continue;
      const bool exact = ctrl.products == Products::kExact;
      if (exact && !(N == 25 && kmax == 10 && n <= 16)) continue;
      if (ctrl.shooting == ShootingScheme::kMultiple && !paper.count({n, N, kmax})) continue;
      const Case c{ctrl, n, N, kmax};
      const std::string tag = ctrl.name() + "/n:" + std::to_string(n) + "/N:" + std::to_string(N);
      benchmark::RegisterBenchmark(("BM_Update/" + tag + "/kmax:" + std::to_string(kmax)).c_str(),
                                   BM_Update, c)
          ->Unit(benchmark::kMicrosecond);
      if (N == 25 && kmax == 10 && ctrl.shooting == ShootingScheme::kSingle) {  // same fixture, right after
        benchmark::RegisterBenchmark(((exact ? "BM_Product/" : "BM_Residual/") + tag).c_str(),
                                     exact ? BM_Product : BM_Residual, c)
            ->Unit(benchmark::kMicrosecond);
      }
    }
  }
  std::vector<std::pair<int, int>> riccati;  // (n, N)
  for (int n : {4, 8, 16, 24, 32}) riccati.emplace_back(n, 25);
  for (int n : {4, 16}) {
    for (int N : {10, 15, 50, 75, 100}) riccati.emplace_back(n, N);
  }
  for (const auto& [n, N] : riccati) {
    for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      benchmark::RegisterBenchmark(
          ("BM_Riccati/" + to_string(f) + "/n:" + std::to_string(n) + "/N:" + std::to_string(N)).c_str(), BM_Riccati,
          f, n, N)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  for (int kmax : {10, 20}) {
    for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      benchmark::RegisterBenchmark(
          ("BM_UnderActuated/" + to_string(f) + "/cartpole/kmax:" + std::to_string(kmax)).c_str(), BM_UnderActuated,
          f, kmax)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  for (int task = 0; task < 3; ++task) {
    for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
      benchmark::RegisterBenchmark(
          ("BM_UnderActuatedRiccati/" + to_string(f) + "/" + kUnderActuatedTasks[task]).c_str(),
          BM_UnderActuatedRiccati, f, task)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  for (int n : {4, 8, 16, 24, 32, 48, 64}) {
    benchmark::RegisterBenchmark(("BM_StageVectorOps/n:" + std::to_string(n)).c_str(),
                                 BM_StageVectorOps, n)
        ->Unit(benchmark::kNanosecond);
  }
}

}  // namespace
}  // namespace idmpc::bench

int main(int argc, char** argv) {
  idmpc::bench::register_all();
  return idmpc::bench::run_benchmarks(argc, argv, 0.2);
}
