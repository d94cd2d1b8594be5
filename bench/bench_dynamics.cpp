// Dynamics layer: one call of each algorithm, and MuJoCo's mj_inverse / mj_forward on identical
// inputs as baselines, on the paper's chains (arm4 and chain8 … chain64).
//
// Every case runs at one random but fixed state (seeded per model); inputs are prepared before
// the timed loop, outputs kept alive with DoNotOptimize. Counter n = number of joints.

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>

#include <utility>

#include "bench_support.hpp"
#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc::bench {
namespace {

// the state every algorithm of one model is timed at, with MuJoCo set up at the same point
struct DynamicsFixture {
  const BenchModel* bm = nullptr;
  std::unique_ptr<Data> data;
  VecX<double> q, v, a, tau, w, x;  // x: right-hand side of M⁻¹x; w: RNEA adjoint seed
  VecX<double> zero, tau_free, qdd;  // BM_FdStageCrbaLtdl's input 0, τ − bias and q̈
  mj::ModelPtr m;  // copy with constraints and actuation off: forces enter as qfrc_applied only
  mj::DataPtr d;
  int n = 0;
};

DynamicsFixture& fixture(const std::string& name) {
  static std::map<std::string, std::unique_ptr<DynamicsFixture>> cache;
  auto& slot = cache[name];
  if (slot) return *slot;
  auto f = std::make_unique<DynamicsFixture>();
  f->bm = &bench_model(name);
  const Model& model = f->bm->model();
  f->n = model.n;
  f->data = std::make_unique<Data>(model);
  // random state: angles anywhere on the circle, moderate rates; seeded by the model size
  std::mt19937 rng(20240 + static_cast<unsigned>(model.n));
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), unit(-1.0, 1.0);
  auto draw = [&](auto& dist) {
    VecX<double> out(model.n);
    for (int i = 0; i < model.n; ++i) out[i] = dist(rng);
    return out;
  };
  f->q = draw(angle);
  f->v = draw(unit);
  f->a = draw(unit);
  f->tau = 10.0 * draw(unit);
  f->w = draw(unit);
  f->x = draw(unit);
  f->zero = f->tau_free = f->qdd = VecX<double>::Zero(model.n);

  // MuJoCo at the same point: constraints and actuation off, ctrl = 0, τ through qfrc_applied
  f->m.reset(mj_copyModel(nullptr, f->bm->m.get()));
  f->m->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_ACTUATION;
  f->d = mj::make_data(f->m.get());
  mju_copy(f->d->qpos, f->q.data(), model.n);
  mju_copy(f->d->qvel, f->v.data(), model.n);
  mju_copy(f->d->qacc, f->a.data(), model.n);
  mju_copy(f->d->qfrc_applied, f->tau.data(), model.n);
  mju_zero(f->d->ctrl, f->m->nu);
  slot = std::move(f);
  return *slot;
}

// times `call(f)` on the model's fixture; `setup(f)` runs once, outside the timed loop
template <typename Setup, typename Call>
void time_kernel(benchmark::State& state, const char* name, Setup&& setup, Call&& call) {
  DynamicsFixture& f = fixture(name);
  setup(f);
  for (auto _ : state) {
    call(f);
    benchmark::ClobberMemory();
  }
  state.counters["n"] = f.n;
}
template <typename Call> void time_kernel(benchmark::State& state, const char* name, Call&& call) {
  time_kernel(state, name, [](DynamicsFixture&) {}, std::forward<Call>(call));
}

const Model& model_of(const DynamicsFixture& f) { return f.bm->model(); }

void BM_Rnea(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    benchmark::DoNotOptimize(rnea(model_of(f), *f.data, f.q, f.v, f.a).data());
  });
}

void BM_Aba(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    benchmark::DoNotOptimize(aba(model_of(f), *f.data, f.q, f.v, f.tau).data());
  });
}

void BM_Crba(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    benchmark::DoNotOptimize(crba(model_of(f), *f.data, f.q).data());
  });
}

void BM_RneaDerivatives(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    rnea_derivatives(model_of(f), *f.data, f.q, f.v, f.a);
    benchmark::DoNotOptimize(f.data->dtau_dq.data());
    benchmark::DoNotOptimize(f.data->dtau_dv.data());
  });
}

void BM_AbaDerivatives(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    aba_derivatives(model_of(f), *f.data, f.q, f.v, f.tau);
    benchmark::DoNotOptimize(f.data->da_dq.data());
    benchmark::DoNotOptimize(f.data->da_dv.data());
    benchmark::DoNotOptimize(f.data->Minv.data());
  });
}

void keep_vjp(DynamicsFixture& f) {
  benchmark::DoNotOptimize(f.data->g_q.data());
  benchmark::DoNotOptimize(f.data->g_v.data());
  benchmark::DoNotOptimize(f.data->g_a.data());
}

// the adjoint triple (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M w as the OCP gets it: the RNEA pass it needs,
// then the reverse sweep
void BM_RneaVjp(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    rnea(model_of(f), *f.data, f.q, f.v, f.a);
    rnea_vjp(model_of(f), *f.data, f.w);
    keep_vjp(f);
  });
}

// the reverse sweep alone, after one RNEA pass outside the loop
void BM_RneaVjpSweepOnly(benchmark::State& state, const char* name) {
  time_kernel(
      state, name, [](DynamicsFixture& f) { rnea(model_of(f), *f.data, f.q, f.v, f.a); },
      [](DynamicsFixture& f) {
        rnea_vjp(model_of(f), *f.data, f.w);
        keep_vjp(f);
      });
}

// M⁻¹x through the articulated inertias of one ABA pass outside the loop
void BM_MinvApply(benchmark::State& state, const char* name) {
  time_kernel(
      state, name, [](DynamicsFixture& f) { aba(model_of(f), *f.data, f.q, f.v, f.tau); },
      [](DynamicsFixture& f) { benchmark::DoNotOptimize(minv_apply(model_of(f), *f.data, f.x).data()); });
}

// M⁻¹x with the sparse LᵀDL factor of M (crba and ltdl_factor outside the loop): Pinocchio's
// cholesky::solve, the counterpart of mj_solveM
void BM_LtdlSolve(benchmark::State& state, const char* name) {
  time_kernel(
      state, name,
      [](DynamicsFixture& f) {
        crba(model_of(f), *f.data, f.q);
        ltdl_factor(model_of(f), *f.data);
      },
      [](DynamicsFixture& f) { benchmark::DoNotOptimize(ltdl_solve(model_of(f), *f.data, f.x).data()); });
}

// the factorization of M (crba outside the loop) and the solve: the counterpart of
// mj_factorM + mj_solveM
void BM_LtdlFactorSolve(benchmark::State& state, const char* name) {
  time_kernel(
      state, name, [](DynamicsFixture& f) { crba(model_of(f), *f.data, f.q); },
      [](DynamicsFixture& f) {
        ltdl_factor(model_of(f), *f.data);
        benchmark::DoNotOptimize(ltdl_solve(model_of(f), *f.data, f.x).data());
      });
}

// The forward work of one FD-adjoint stage, two ways: q̈ = FD(q, v, τ), μ = M⁻¹x and the RNEA
// pass at (q, v, q̈) that the adjoint sweep needs. As FD adjoint does it: ABA, M⁻¹x through its
// factorization, the RNEA forces from its pass.
void BM_FdStageAba(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    const Model& model = model_of(f);
    aba(model, *f.data, f.q, f.v, f.tau);
    benchmark::DoNotOptimize(minv_apply(model, *f.data, f.x).data());
    benchmark::DoNotOptimize(rnea_after_aba(model, *f.data, f.q, f.v).data());
  });
}

// … and through M: the bias RNEA(q, v, 0), CRBA, the sparse factor, two solves, then RNEA at
// (q, v, q̈)
void BM_FdStageCrbaLtdl(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    const Model& model = model_of(f);
    Data& data = *f.data;
    f.tau_free = f.tau - rnea(model, data, f.q, f.v, f.zero);
    crba(model, data, f.q);
    ltdl_factor(model, data);
    f.qdd = ltdl_solve(model, data, f.tau_free);
    benchmark::DoNotOptimize(ltdl_solve(model, data, f.x).data());
    benchmark::DoNotOptimize(rnea(model, data, f.q, f.v, f.qdd).data());
  });
}

// dense M⁻¹ from q (as Pinocchio's computeMinverse)
void BM_Minv(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    benchmark::DoNotOptimize(minv_matrix(model_of(f), *f.data, f.q).data());
  });
}

// dense M⁻¹ after an ABA pass outside the loop (the sweeps of every unit load)
void BM_MinvAfterAba(benchmark::State& state, const char* name) {
  time_kernel(
      state, name, [](DynamicsFixture& f) { aba(model_of(f), *f.data, f.q, f.v, f.tau); },
      [](DynamicsFixture& f) { benchmark::DoNotOptimize(minv_matrix_after_aba(model_of(f), *f.data).data()); });
}

// baseline of RNEA: qfrc_inverse at (qpos, qvel, qacc)
void BM_MjInverse(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    mj_inverse(f.m.get(), f.d.get());
    benchmark::DoNotOptimize(f.d->qfrc_inverse);
  });
}

// baseline of ABA: qacc at (qpos, qvel) with qfrc_applied = τ, no constraints
void BM_MjForward(benchmark::State& state, const char* name) {
  time_kernel(state, name, [](DynamicsFixture& f) {
    mj_forward(f.m.get(), f.d.get());
    benchmark::DoNotOptimize(f.d->qacc);
  });
}

// baseline of M⁻¹x: MuJoCo's solve with the sparse LTDL factor of one mj_forward outside the loop
void BM_MjSolveM(benchmark::State& state, const char* name) {
  time_kernel(
      state, name, [](DynamicsFixture& f) { mj_forward(f.m.get(), f.d.get()); },
      [](DynamicsFixture& f) {
        mj_solveM(f.m.get(), f.d.get(), f.d->qfrc_smooth, f.x.data(), 1);
        benchmark::DoNotOptimize(f.d->qfrc_smooth);
      });
}

// M⁻¹x at a new point for MuJoCo: the sparse LTDL factorization of M (qM from one mj_forward
// outside the loop), then the solve; what minv_apply after aba is to ABA
void BM_MjFactorSolveM(benchmark::State& state, const char* name) {
  time_kernel(
      state, name, [](DynamicsFixture& f) { mj_forward(f.m.get(), f.d.get()); },
      [](DynamicsFixture& f) {
        mj_factorM(f.m.get(), f.d.get());
        mj_solveM(f.m.get(), f.d.get(), f.d->qfrc_smooth, f.x.data(), 1);
        benchmark::DoNotOptimize(f.d->qfrc_smooth);
      });
}

// one case per model: the paper's arm and chains, plus two larger generated chains
#define IDMPC_BENCH_MODELS(BM)             \
  BENCHMARK_CAPTURE(BM, arm4, "arm4");     \
  BENCHMARK_CAPTURE(BM, chain8, "chain8");   \
  BENCHMARK_CAPTURE(BM, chain16, "chain16"); \
  BENCHMARK_CAPTURE(BM, chain24, "chain24"); \
  BENCHMARK_CAPTURE(BM, chain32, "chain32"); \
  BENCHMARK_CAPTURE(BM, chain48, "chain48"); \
  BENCHMARK_CAPTURE(BM, chain64, "chain64");               \
  BENCHMARK_CAPTURE(BM, chain8_spatial, "chain8_spatial");   \
  BENCHMARK_CAPTURE(BM, chain32_spatial, "chain32_spatial")

IDMPC_BENCH_MODELS(BM_Rnea);
IDMPC_BENCH_MODELS(BM_MjInverse);
IDMPC_BENCH_MODELS(BM_Aba);
IDMPC_BENCH_MODELS(BM_MjForward);
IDMPC_BENCH_MODELS(BM_Crba);
IDMPC_BENCH_MODELS(BM_RneaDerivatives);
IDMPC_BENCH_MODELS(BM_AbaDerivatives);
IDMPC_BENCH_MODELS(BM_RneaVjp);
IDMPC_BENCH_MODELS(BM_RneaVjpSweepOnly);
IDMPC_BENCH_MODELS(BM_MinvApply);
IDMPC_BENCH_MODELS(BM_LtdlSolve);
IDMPC_BENCH_MODELS(BM_MjSolveM);
IDMPC_BENCH_MODELS(BM_LtdlFactorSolve);
IDMPC_BENCH_MODELS(BM_MjFactorSolveM);
IDMPC_BENCH_MODELS(BM_FdStageAba);
IDMPC_BENCH_MODELS(BM_FdStageCrbaLtdl);
IDMPC_BENCH_MODELS(BM_Minv);
IDMPC_BENCH_MODELS(BM_MinvAfterAba);

}  // namespace
}  // namespace idmpc::bench

int main(int argc, char** argv) {
  idmpc::bench::stagger_mujoco_allocations();  // MuJoCo's baselines at their best (see there)
  return idmpc::bench::run_benchmarks(argc, argv, 0.2);
}
