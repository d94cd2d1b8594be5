#pragma once
/// @file count_allocations.hpp
/// @brief Counting heap allocations in a test, for code compiled without Eigen's runtime
/// allocation check: the executable defines malloc, calloc and realloc over glibc's own entry
/// points, which take precedence over libc's; under AddressSanitizer, whose runtime owns malloc,
/// it counts through the runtime's allocation hook instead. It defines those functions: include
/// it in exactly one file of a test executable.

#include <atomic>
#include <cstddef>

#include "idmpc/spatial/spatial.hpp"
#include "support/sanitizers.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if IDMPC_TEST_ASAN
// the sanitizer runtime's hook (sanitizer/allocator_interface.h, which gcc does not install)
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*)(const volatile void*, std::size_t),
                                                         void (*)(const volatile void*));
namespace {
void malloc_hook(const volatile void*, std::size_t) { count(); }
void free_hook(const volatile void*) {}
// installed before main, so before any test runs
[[maybe_unused]] const int g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(malloc_hook, free_hook);
}  // namespace
#else
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* malloc(std::size_t size) {
  count();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  count();
  return __libc_realloc(p, size);
}
}
#endif

namespace idmpc::test {

/// @brief Allocations counted over the guard's lifetime.
class CountAllocations {
 public:
  CountAllocations() {
    g_allocations = 0;
    g_counting = true;
  }
  ~CountAllocations() { g_counting = false; }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
  long count() const { return g_allocations.load(); }
};

/// @brief Allocations the counter sees for one Eigen vector of 7 (≥ 1 when it is armed: else a
/// test that finds none proves nothing).
inline long allocations_of_a_vector() {
  CountAllocations c;
  VecX<double> x(7);
  x.setZero();
  asm volatile("" : : "g"(x.data()) : "memory");  // the vector escapes: clang may not elide it
  return c.count();
}

}  // namespace idmpc::test
