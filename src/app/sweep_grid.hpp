#pragma once
/// @file sweep_grid.hpp
/// @brief The grid of `idmpc sweep`: its options, its cells (each one closed-loop run, known by
/// every axis and setting it runs with) and the task each cell runs.

#include <string>
#include <vector>

#include "idmpc/experiment/task.hpp"

namespace idmpc::app {

/// @brief The options of `idmpc sweep` (its --help says what each does).
struct SweepOptions {
  std::string out_dir = "results/sweep";
  std::string models_dir;             // empty: mjcf/ of the data directory
  std::string tables = "all";        // 12, 3, all or arms
  std::string arms_tasks;            // arms: the list of tasks; empty: arms.json of models_dir
  std::string offset_free = "task";  // arms: task (each task's own setting), on, off or both
  std::string derivatives = "matrix";  // matrix, adjoint or both
  std::string shooting = "single";     // single, multiple or both
  std::string products = "difference"; // difference, exact or both
  std::string solver = "cgmres";       // cgmres, riccati or both
  double duration = 10.0;
  bool duration_given = false;  // arms: the task files' own durations unless --duration is given
  bool logs = false;
  bool simd_stages = true;  // false: --no-simd-stages, every run stage by stage (the paper's arithmetic)
  std::vector<std::string> latency = {"none"};  // the compute latencies each cell runs with (an axis)
};

/// @brief The real-arm grids: each task of a list under both formulations; arms: mjcf/arms.json
/// (reach tasks), tracking: mjcf/tracking.json (frame targets that move), unless --arms-tasks.
inline constexpr const char* kArmsTable = "arms";
inline constexpr const char* kTrackingTable = "tracking";
/// @brief Whether `table` is one of the real-arm grids (arms, tracking).
bool task_table(const std::string& table);
/// @brief The work-precision grid: mjcf/work_precision.json lists the paper's models (the
/// swing-up on each), real arms' task files and the kmax values.
inline constexpr const char* kWorkPrecisionTable = "work-precision";
/// @brief Whether a cell of `table` on `model` runs a task file (a real arm's) rather than the
/// paper's task on a model.
bool runs_task_file(const std::string& table, const std::string& model);

/// @brief A cell of the grid: one closed-loop run.
struct Cell {
  // arms: model is the task file as the list names it
  std::string table, model, formulation, derivatives, shooting;
  int n = 0, N = 0, kmax = 0;
  std::string settings;      // hash of everything else the cell runs with (the task as run)
  bool offset_free = false;  // offset-free tracking (the disturbance observer) on
  std::string products = "difference";  // how C/GMRES forms its products (formulations.md §Exact products)
  std::string latency = "none";         // compute latency (Task::latency)
  std::string solver = "cgmres";        // the solver family (docs/solvers.md)
  // the resume key: every axis and setting the cell runs with. A cell's ID (--list-cells, --cell)
  // is its hash, so an axis added here reaches the cell runs with no other change.
  std::string key() const {
    return table + "|" + model + "|" + formulation + "|" + derivatives + "|" + shooting + "|" +
           (offset_free ? "offset-free" : "-") + "|" + std::to_string(N) + "|" + std::to_string(kmax) + "|" +
           products + "|" + settings + (latency == "none" ? "" : "|latency " + latency) +
           (solver == "cgmres" ? "" : "|solver " + solver);
  }
  // the solver variant, as the tables label it
  std::string variant() const {
    if (solver == "riccati") return "Riccati SQP-RTI";
    return derivatives + (shooting == "single" ? "" : ", " + shooting + " shooting") +
           (products == "difference" ? "" : ", " + products + " products");
  }
  bool runs_task_file() const { return app::runs_task_file(table, model); }
};

/// @brief The list of tasks of the arms table: --arms-tasks, or arms.json of the models directory.
std::string arms_list(const SweepOptions& opt);

/// @brief The file a cell runs: the paper's model, or an arm's task file (relative to its list's
/// directory).
std::string cell_file(const SweepOptions& opt, const Cell& c);

/// @brief The task a cell runs: the paper's on the cell's model, or an arm's own task file.
Task cell_task(const Task& base, const Cell& c, const SweepOptions& opt);

/// @brief The grid, each cell keyed by the settings it runs with.
std::vector<Cell> grid(const SweepOptions& opt, const PaperTables& tables, const Task& base);

/// @brief The cell as the progress lines and errors name it.
std::string cell_label(const Cell& c);

}  // namespace idmpc::app
