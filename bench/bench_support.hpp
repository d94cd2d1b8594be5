#pragma once
/// @file bench_support.hpp
/// @brief What both benchmark binaries share: the paper's chain models by size (mjcf/ files,
/// or tools/gen_chain.py for sizes that have no file), loaded once and kept for the process,
/// the default minimum time per case, and the build facts recorded in the JSON context.

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::bench {

/// A MuJoCo model and the controller's Model imported from it.
struct BenchModel {
  BenchModel(std::string name_, mj::ModelPtr m_)
      : name(std::move(name_)), m(std::move(m_)), imported(mj::import_model(m.get(), name)) {}

  std::string name;
  mj::ModelPtr m;
  mj::ImportedModel imported;
  const Model& model() const { return imported.model; }
  int n() const { return imported.model.n; }
};

/// "arm4" for n = 4 (the paper's 4-link arm), "chain<n>" otherwise.
inline std::string chain_name(int n) { return n == 4 ? "arm4" : "chain" + std::to_string(n); }

/// MJCF text of the n-link chain written by tools/gen_chain.py (alternating axes if spatial).
inline std::string generate_chain(int n, bool spatial = false) {
  const std::string cmd = "/usr/bin/python3 " IDMPC_SOURCE_DIR "/tools/gen_chain.py -n " +
                          std::to_string(n) + (spatial ? " --nonplanar" : "");
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) throw std::runtime_error("could not run " + cmd);
  std::string xml;
  char buf[4096];
  for (size_t got; (got = fread(buf, 1, sizeof buf, pipe)) > 0;) xml.append(buf, got);
  if (pclose(pipe) != 0 || xml.empty()) throw std::runtime_error("'" + cmd + "' failed");
  return xml;
}

/// The model "arm4", "chain<n>" or "chain<n>_spatial": mjcf/<name>.xml if it exists, else
/// generated. Cached.
inline const BenchModel& bench_model(const std::string& name) {
  static std::map<std::string, std::unique_ptr<BenchModel>> cache;
  auto& slot = cache[name];
  if (!slot) {
    const std::string path = IDMPC_SOURCE_DIR "/mjcf/" + name + ".xml";
    mj::ModelPtr m;
    if (std::ifstream(path).good()) {
      m = mj::load_model(path);
    } else if (name.rfind("chain", 0) == 0) {
      const bool spatial = name.size() > 8 && name.compare(name.size() - 8, 8, "_spatial") == 0;
      m = mj::load_model_from_string(generate_chain(std::stoi(name.substr(5)), spatial));
    } else {
      throw std::invalid_argument("no model file " + path);
    }
    slot = std::make_unique<BenchModel>(name, std::move(m));
  }
  return *slot;
}

inline const BenchModel& bench_model(int n) { return bench_model(chain_name(n)); }

/// @brief Places MuJoCo's allocations (model copies, data arenas) at staggered offsets within
/// pages, so that its timings are its best in every run. How fast mj_inverse and mj_forward run
/// depends on where their buffers sit relative to each other: page-aligned, or staggered by
/// 576 bytes, they took 1.5× the time (2.0 against 1.35 µs at n = 4) on the reference machine —
/// likely 4K aliasing between arrays — and with plain malloc which of the two a run got
/// depended on what had been allocated before (a benchmark filter, a new kernel's fixture).
/// Staggered by 1088, 2112 or 3136 bytes per allocation, every run tried was at the fast level.
/// Call before MuJoCo allocates anything; the hooks stay for the process.
inline void stagger_mujoco_allocations() {
  mju_user_malloc = [](size_t size) -> void* {
    static std::atomic<size_t> count{0};
    constexpr size_t kPage = 4096, kStep = 1088, kHeader = 64;  // 64: room for the base pointer
    const size_t offset = kHeader + (count++ * kStep) % kPage;
    void* base = std::aligned_alloc(kPage, (size + offset + kPage - 1) / kPage * kPage);
    if (!base) return nullptr;
    char* p = static_cast<char*>(base) + offset;
    std::memcpy(p - sizeof(void*), &base, sizeof(void*));
    return p;
  };
  mju_user_free = [](void* p) {
    if (!p) return;
    void* base = nullptr;
    std::memcpy(&base, static_cast<char*>(p) - sizeof(void*), sizeof(void*));
    std::free(base);
  };
}

/// Runs the registered benchmarks with a default --benchmark_min_time of `min_time` seconds
/// (a command-line value wins) and records the compiler and build type in the JSON context.
inline int run_benchmarks(int argc, char** argv, double min_time) {
  std::vector<char*> args(argv, argv + argc);
  bool has_min_time = false;
  for (int i = 1; i < argc; ++i) {
    has_min_time |= std::string(argv[i]).rfind("--benchmark_min_time", 0) == 0;
  }
  std::string min_time_arg = "--benchmark_min_time=" + std::to_string(min_time);
  if (!has_min_time) args.push_back(min_time_arg.data());
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
#if defined(__clang__)
  benchmark::AddCustomContext("compiler", "clang " __clang_version__);
#elif defined(__GNUC__)
  benchmark::AddCustomContext("compiler", "gcc " __VERSION__);
#endif
#ifdef NDEBUG
  benchmark::AddCustomContext("idmpc_build_type", "release (NDEBUG)");
#else
  benchmark::AddCustomContext("idmpc_build_type", "debug (asserts on)");
#endif
#ifdef __OPTIMIZE__
  benchmark::AddCustomContext("idmpc_optimized", "yes");
#else
  benchmark::AddCustomContext("idmpc_optimized", "no");
#endif
#ifdef __AVX2__
  benchmark::AddCustomContext("idmpc_simd", "avx2");
#elif defined(__SSE2__)
  benchmark::AddCustomContext("idmpc_simd", "sse2");
#endif
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace idmpc::bench
