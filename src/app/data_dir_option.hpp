#pragma once
/// @file data_dir_option.hpp
/// @brief --data-dir, the option of every command that reads shipped data (the paper's task and
/// tables, the models of mjcf/): it sets idmpc::set_data_dir before the command runs.

#include <CLI/CLI.hpp>

namespace idmpc::app {

/// @brief Adds --data-dir DIR to `sub`; a DIR without mjcf/ is a one-line error naming it.
void add_data_dir_option(CLI::App& sub);

}  // namespace idmpc::app
