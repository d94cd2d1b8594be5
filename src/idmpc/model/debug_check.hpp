#pragma once
/// @file debug_check.hpp
/// @brief IDMPC_DEBUG_CHECK(condition, message): a precondition of a hot path, checked in debug
/// builds (no NDEBUG, or IDMPC_DEBUG_CHECKS=1) and compiled out otherwise. A failed check
/// prints the message with its place and aborts, like assert.

#include <cstdio>
#include <cstdlib>

#ifndef IDMPC_DEBUG_CHECKS
#ifdef NDEBUG
#define IDMPC_DEBUG_CHECKS 0
#else
#define IDMPC_DEBUG_CHECKS 1
#endif
#endif

namespace idmpc::detail {

[[noreturn]] inline void debug_check_failed(const char* condition, const char* message,
                                            const char* file, int line) {
  std::fprintf(stderr, "%s:%d: idmpc debug check failed: %s (%s)\n", file, line, message,
               condition);
  std::abort();
}

}  // namespace idmpc::detail

#if IDMPC_DEBUG_CHECKS
#define IDMPC_DEBUG_CHECK(condition, message)                                              \
  ((condition) ? static_cast<void>(0)                                                     \
               : ::idmpc::detail::debug_check_failed(#condition, message, __FILE__, __LINE__))
#else
#define IDMPC_DEBUG_CHECK(condition, message) static_cast<void>(0)
#endif
