#pragma once
/// @file commands.hpp
/// @brief The idmpc sub-commands; each file in src/app registers one.

#include <CLI/CLI.hpp>

namespace idmpc::app {

void register_check(CLI::App& app);
void register_dynamics(CLI::App& app);
void register_swingup(CLI::App& app);
void register_sweep(CLI::App& app);
void register_render(CLI::App& app);

}  // namespace idmpc::app
