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

/// @brief A two-joint arm (two boxes, motors with declared ctrlrange) as MJCF text, for tests of
/// bad model values: `attribute` (e.g. `ctrlrange="nan 1"`) goes on the element named `element`
/// ("link0", "joint0", "geom0", "motor0"; "inertial1" adds an `<inertial>` to link1 with it),
/// `extra` before `</mujoco>` (e.g. a keyframe).
std::string arm2_mjcf(const std::string& element = "", const std::string& attribute = "", const std::string& extra = "");

}  // namespace idmpc::test
