#pragma once
/// @file swingup.hpp
/// @brief One closed-loop run of a task (idmpc/experiment/task.hpp), as used by `swingup` and
/// `sweep`: the task file gives the experiment, command-line options override it.

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "idmpc/experiment/run_record.hpp"
#include "idmpc/mujoco/closed_loop.hpp"

namespace idmpc::app {

/// @brief Command-line options that override a task's fields; only those given are applied.
struct TaskOverrides {
  std::string task_file;  ///< --task; empty: the paper's swing-up
  std::string model;      ///< positional MODEL
  Task values;            ///< parsed values, applied where the option was given
  bool fallback = false;  ///< --fallback: run_swingup's Q_a fallback
  std::vector<std::pair<CLI::Option*, void (*)(const Task&, Task&)>> given;
};

/// @brief The check of a --latency value (parse_latency): none, measured or a compute time in ms.
CLI::Validator latency_check();

/// @brief Adds --task, MODEL and the task options (--formulation, --N, --Qq, …) to a command.
void add_task_options(CLI::App& sub, TaskOverrides& o);

/// @brief The task file (or the paper's) with the given options applied.
Task make_task(const TaskOverrides& o);

/// @brief Outcome of one run with its summary (the JSON written by --summary).
struct SwingupOutcome {
  mj::RunResult result;
  RunSummary summary;
};

/// @brief Runs the task; streams the CSV log to `log_path` if non-empty (temporary file
/// renamed when the run ends, diverged or not). Throws on bad settings before any output.
/// With `fallback`, an ID run with Q_a = 0 that diverges is rerun with the task's
/// weights.Qa_fallback (the paper's rule); the summary's warnings say so, the log is the rerun's.
SwingupOutcome run_swingup(const Task& task, const std::string& log_path, bool fallback = false);

/// @brief Writes JSON to a file atomically.
void write_json(const nlohmann::json& j, const std::string& path);

/// @brief One-screen human summary of a run.
std::string human_summary(const RunSummary& s);

}  // namespace idmpc::app
