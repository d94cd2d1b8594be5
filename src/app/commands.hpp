#pragma once
/// @file commands.hpp
/// @brief The idmpc sub-commands; each file in src/app registers one.

#include <CLI/CLI.hpp>

namespace idmpc::app {

/// @brief Exit codes of a run that ended without an error (an error exits with 1): `swingup`
/// exits with kReached when the target was reached (max|q − q_ref| at the end below the task's
/// reach_tolerance), kNotReached when the run completed without reaching it, kDiverged when the
/// controller diverged (log and summary are written in every case).
enum ExitCode : int { kReached = 0, kNotReached = 2, kDiverged = 3 };

/// @brief The exit code a command's callback sets for main to return (0 unless set).
int& command_exit_code();

void register_check(CLI::App& app);
void register_dynamics(CLI::App& app);
void register_swingup(CLI::App& app);
void register_sweep(CLI::App& app);
void register_render(CLI::App& app);

}  // namespace idmpc::app
