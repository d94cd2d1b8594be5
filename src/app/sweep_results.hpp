#pragma once
/// @file sweep_results.hpp
/// @brief A cell's run and its result: the figures a cell's run gives, and its row in the sweep's
/// CSV files (sweep.csv, arms.csv, …, and a cell's record), written and read back.

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "app/sweep_grid.hpp"

namespace idmpc::app {

/// @brief What a cell's run gave.
struct CellResult {
  Cell cell;
  double Qa = 0;
  bool diverged = false;
  double diverged_at = NAN, mean_ms = NAN, p95_ms = NAN, final_q_error = NAN, final_v_norm = NAN;
  long steps = 0, saturated_steps = 0;   // steps run; steps with a clamped torque
  double max_violation = NAN;            // of the OCP's torques over their bounds [N m]
  // the target reached: not diverged, final max|q − q_ref| below the task's reach_tolerance
  bool reached = false;
  double reach_tolerance = NAN;
  long contact_steps = 0;                // control steps with a contact in the plant
  double max_contact_force = NAN;        // the largest contact normal force [N]
  double final_disturbance = NAN;        // max|d̂| of the observer at the end [N m] (0 when off)
  // a frame target's tracking error: position [m] and orientation [rad], RMS and max (NaN without)
  double position_rms = NAN, position_max = NAN, orientation_rms = NAN, orientation_max = NAN;
  double tracking_tolerance = NAN;
  double mean_residual = NAN;     // mean ‖F‖ over the updates
  double closed_loop_cost = NAN;  // ∫ L dt of the task's stage cost along the run
  // compute latency: updates run, those slower than the control period, the slowest [ms], and the
  // tracking cost (RMS of |q - q_ref| over the run)
  long updates = 0, deadline_misses = 0;
  double max_ms = NAN, joint_error_rms = NAN;
};

/// @brief The paper's figure for a cell (mjcf/paper_tables.json).
struct PaperFigure {
  double ms;
  std::string note;
};
PaperFigure paper_figure(const PaperTables& tables, const Cell& c);

/// @brief The header line of the CSV files: their columns.
std::string csv_header();

/// @brief A cell's row of the CSV files.
std::string csv_row(const PaperTables& tables, const CellResult& r);

/// @brief Finished cells of an earlier, possibly interrupted, sweep of this grid (CRLF line ends
/// accepted; a torn last line, as an interrupted append leaves it, is dropped). A file of
/// another format or with cells of other settings is refused, never overwritten.
std::map<std::string, CellResult> read_finished(const std::string& path, const std::vector<Cell>& cells);

/// @brief The file name of a cell's --logs log in the output directory.
std::string log_name(const Cell& c);

/// @brief Runs a cell after a progress line's start: an error goes on a line of its own.
CellResult run_cell_after_progress(const Task& base, const Cell& c, const SweepOptions& opt);

}  // namespace idmpc::app
