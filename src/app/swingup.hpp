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

/// @brief What a run says on standard error while it runs (warnings always).
struct RunMessages {
  bool notices = true;    ///< what the run does with the model and chose by itself, before it starts
  /// @brief The wall time between two progress lines [s] (how far the run is and how far from its
  /// target; during a long start, that it is still solving it); 0: at every step and every
  /// iteration of the start; negative: none.
  double progress_period = -1;
};
/// @brief The default wall time between two progress lines of `swingup` [s].
inline constexpr double kProgressPeriod = 2.0;

/// @brief Runs the task; streams the CSV log to `log_path` if non-empty (temporary file
/// renamed when the run ends, diverged or not). Throws on bad settings before any output.
/// With `fallback`, an ID run with Q_a = 0 that diverges is rerun with the task's
/// weights.Qa_fallback (the paper's rule); the summary's warnings say so, the log is the rerun's.
SwingupOutcome run_swingup(const Task& task, const std::string& log_path, bool fallback = false,
                           const RunMessages& messages = {});

/// @brief Writes JSON to a file atomically.
void write_json(const nlohmann::json& j, const std::string& path);

/// @brief One-screen human summary of a run.
std::string human_summary(const RunSummary& s);

}  // namespace idmpc::app
