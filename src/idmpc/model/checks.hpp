#pragma once
/// @file checks.hpp
/// @brief The two kinds of precondition checks of the library.
///
/// IDMPC_CHECK_ARGUMENT(condition, message): a precondition at the public API boundary — the
/// sizes of the vectors passed in, the parts a Data was made with — checked in every build, as
/// Pinocchio's PINOCCHIO_CHECK_ARGUMENT_SIZE: a failed check throws std::invalid_argument with
/// the message (a string literal: nothing is allocated unless the check fails). A few integer
/// comparisons per call; their cost per control update is in docs/testing.md.
///
/// IDMPC_DEBUG_CHECK(condition, message): a precondition that costs real work to check (that
/// data holds the passes of another kernel at this very (q, v)), checked in debug builds (no
/// NDEBUG, or IDMPC_DEBUG_CHECKS=1: the sanitizer build) and compiled out otherwise. A failed
/// check prints the message with its place and aborts, like assert; a program that must not
/// abort (the Python module) sets detail::debug_check_handler, which throws instead.

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#ifndef IDMPC_DEBUG_CHECKS
#ifdef NDEBUG
#define IDMPC_DEBUG_CHECKS 0
#else
#define IDMPC_DEBUG_CHECKS 1
#endif
#endif

namespace idmpc::detail {

/// @brief Called with the failed check's text ("<file>:<line>: idmpc debug check failed:
/// <message> (<condition>)") instead of aborting, when set; it must throw (if it returns, the
/// process aborts as without it). Set once, before any check can run.
inline void (*debug_check_handler)(const char* text) = nullptr;

[[noreturn]] inline void debug_check_failed(const char* condition, const char* message,
                                            const char* file, int line) {
  char text[1024];
  std::snprintf(text, sizeof text, "%s:%d: idmpc debug check failed: %s (%s)", file, line, message, condition);
  if (debug_check_handler != nullptr) debug_check_handler(text);
  std::fprintf(stderr, "%s\n", text);
  std::abort();
}

[[noreturn]] inline void argument_check_failed(const char* message) { throw std::invalid_argument(message); }

}  // namespace idmpc::detail

#define IDMPC_CHECK_ARGUMENT(condition, message) \
  ((condition) ? static_cast<void>(0) : ::idmpc::detail::argument_check_failed(message))

#if IDMPC_DEBUG_CHECKS
#define IDMPC_DEBUG_CHECK(condition, message)                                              \
  ((condition) ? static_cast<void>(0)                                                     \
               : ::idmpc::detail::debug_check_failed(#condition, message, __FILE__, __LINE__))
#else
#define IDMPC_DEBUG_CHECK(condition, message) static_cast<void>(0)
#endif
