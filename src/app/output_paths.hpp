#pragma once
/// @file output_paths.hpp
/// @brief Checks of output paths made before a command does any work: no output may be one of
/// its inputs, two outputs may not be the same file, and an output may not be a directory or
/// lie in a directory that does not exist.

#include <string>
#include <vector>

namespace idmpc::app {

/// @brief A path with the option (or argument) that names it, for messages: {"--out", "x.csv"}.
struct NamedPath {
  std::string option;
  std::string path;
};

/// @brief Refuses outputs that would destroy an input or each other.
///
/// Two paths are the same file if they are the same inode (std::filesystem::equivalent, after
/// following symbolic links) or, for files not there yet, the same canonical path. Empty paths
/// (options not given) are skipped. Character devices (/dev/null, a terminal) are exempt: many
/// outputs, or an input and an output, may share one.
/// @throws std::invalid_argument naming both options and paths, e.g. "--out 'x.csv' is the
/// same file as --in 'x.csv': expected a different output file"
void check_output_paths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

}  // namespace idmpc::app
