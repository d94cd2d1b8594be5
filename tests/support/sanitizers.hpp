#pragma once
/// @file sanitizers.hpp
/// @brief IDMPC_TEST_ASAN: 1 when this translation unit is built with AddressSanitizer, by gcc
/// (__SANITIZE_ADDRESS__) or clang (__has_feature(address_sanitizer)); tools/sanitize.sh uses clang.

#if defined(__SANITIZE_ADDRESS__)
#define IDMPC_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IDMPC_TEST_ASAN 1
#endif
#endif
#ifndef IDMPC_TEST_ASAN
#define IDMPC_TEST_ASAN 0
#endif
