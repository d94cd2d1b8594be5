#pragma once
/// @file output_paths.hpp
/// @brief Checks of output paths made before a command does any work: no output may be one of
/// its inputs, two outputs may not be the same file, and an output may not be a directory or
/// lie in a directory that does not exist.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace idmpc::app {

/// @brief A path with the option (or argument) that names it, for messages: {"--out", "x.csv"}.
struct NamedPath {
  std::string option;
  std::string path;
};

/// @brief Refuses outputs that would destroy an input or each other.
///
/// Two paths are the same file if they are the same inode (after following symbolic links) or,
/// for files not there yet, the same absolute canonical path (so `a.csv`, `./a.csv`,
/// `d/../a.csv` and `$PWD/a.csv` are one file). Empty paths
/// (options not given) are skipped. Character devices (/dev/null, a terminal) are exempt: many
/// outputs, or an input and an output, may share one.
/// @throws std::invalid_argument naming both options and paths, e.g. "--out 'x.csv' is the
/// same file as --in 'x.csv': expected a different output file"
void check_output_paths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

/// @brief The files a model reads, as inputs for check_output_paths: the model itself ({"model",
/// path}), the files its MJCF includes ({"model's include", …}) and its asset files (meshes,
/// textures, …: {"model's mesh", …}), as the pre-scan of idmpc/mujoco/mjcf_scan.hpp finds them.
std::vector<NamedPath> model_inputs(const std::string& model, const std::string& option = "model");

/// @brief Refuses paths that are not valid UTF-8 (each named by its option), for paths that a
/// JSON output records: checked before any work, so that no run ends unable to write its JSON.
/// @throws std::invalid_argument "--log '…': expected a UTF-8 file name (it is recorded in the
/// JSON summary)"
void check_utf8_paths(const std::vector<NamedPath>& paths, const std::string& why);

/// @brief A CLI11 check for an output option: an empty path is refused ("--log: expected a
/// file path, got ''"), an option not given is not checked.
CLI::Validator non_empty_path();

}  // namespace idmpc::app
