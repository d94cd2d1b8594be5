#pragma once
/// @file test_models.hpp
/// @brief The model files shipped in mjcf/, for tests that run on every model.

#include <string>
#include <vector>

namespace idmpc::test {

/// @brief Absolute paths of all *.xml files under IDMPC_SOURCE_DIR/mjcf, sorted (hidden files,
/// a generator's temporaries, are skipped).
/// @throws std::runtime_error if the directory is missing or holds no model.
std::vector<std::string> shipped_model_paths();

}  // namespace idmpc::test
