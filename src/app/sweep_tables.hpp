#pragma once
/// @file sweep_tables.hpp
/// @brief The Markdown tables of a sweep (sweep.md, arms.md, tracking.md, work_precision.md): our
/// figures beside the paper's, the real arms' runs and outcomes, the work-precision verdict and
/// the latency table.

#include <map>
#include <string>
#include <vector>

#include "app/sweep_grid.hpp"
#include "app/sweep_results.hpp"

namespace idmpc::app {

/// @brief A figure as the tables print it, to `precision` significant digits; "–" for NaN.
std::string fmt(double x, int precision = 3);

/// @brief What the tables' matrix mode is, for the tables' headers.
std::string stages_note(const SweepOptions& opt);

/// @brief The solver variants of a grid (Cell::variant: derivatives, shooting), in the grid's order.
std::vector<std::string> variants(const std::vector<Cell>& cells);

// the tables of the task lists, arms and tracking (sweep_arms_tables.cpp)

/// @brief The real-arm tables: time per update with ID/FD, then each run's outcome.
std::string arms_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                          const std::map<std::string, CellResult>& done);

/// @brief The tracking table: per task (and offset-free setting) and variant, FD beside ID: ms per
/// update and the frame's position error, RMS and max over the run, with the orientation error.
std::string tracking_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                              const std::map<std::string, CellResult>& done);

/// @brief The tables of the grid, with the latency table when the latency axis has more than none.
std::string markdown_with_latency(const PaperTables& tables, const std::vector<Cell>& cells,
                                  const std::map<std::string, CellResult>& done, const SweepOptions& opt);

}  // namespace idmpc::app
