#pragma once
/// @file data_dir.hpp
/// @brief Where idmpc's shipped data lives: the directory holding `mjcf/` (models, task files,
/// paper_tables.json, arms.json). Every path to shipped data is built from data_dir().
///
/// The lookup, first match wins:
///   1. set_data_dir(dir) (the command line's --data-dir);
///   2. the environment variable IDMPC_DATA_DIR;
///   3. `<directory of the running executable>/` IDMPC_DATA_RELATIVE_DIR (`../share/idmpc`):
///      the installed layout `<prefix>/bin` + `<prefix>/share/idmpc`, which the build tree
///      mirrors with `<build>/share/idmpc/mjcf`, a link to the sources' mjcf/.
/// A directory given by 1 or 2 must hold mjcf/; a wrong one is an error, not a fallback.

#include <string>

namespace idmpc {

/// @brief The name of the environment variable that sets the data directory.
inline constexpr const char* kDataDirVariable = "IDMPC_DATA_DIR";

/// @brief The data directory (it holds mjcf/), found as described above. Throws
/// std::runtime_error naming what was tried and how to set it when no candidate holds mjcf/.
std::string data_dir();

/// @brief Sets the data directory for this process (before IDMPC_DATA_DIR and the executable's
/// directory); an empty `dir` clears the setting. Throws std::invalid_argument when `dir` does
/// not hold mjcf/.
void set_data_dir(const std::string& dir);

/// @brief A shipped file: data_dir()/mjcf/`file`, with the links of that path resolved (an
/// absolute path; in a build tree, the file's place in the sources).
std::string shipped_mjcf_path(const std::string& file);

}  // namespace idmpc
