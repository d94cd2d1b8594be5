#pragma once
/// @file errors.hpp
/// @brief The message a call throws, for tests of error messages.

#include <exception>
#include <functional>
#include <string>

namespace idmpc::test {

/// @brief what() of the exception `f` throws, or "no exception".
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no exception";
}

}  // namespace idmpc::test
