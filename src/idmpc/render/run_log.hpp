#pragma once
/// @file run_log.hpp
/// @brief Run logs (idmpc/experiment/run_record.hpp) checked against the model they replay on.

#include <string>

#include <mujoco/mujoco.h>

#include "idmpc/experiment/run_record.hpp"

namespace idmpc::render {

using idmpc::read_run_log;
using idmpc::RunLog;

/// @brief Checks that a log fits a model: its joint count, with the joints its summary says the
/// controller held, equals the model's nq (each held joint one of the model's), and when the
/// log's summary records the hash of the model file it ran on, `model_path` has that hash.
/// Throws std::invalid_argument ("log 'x.csv' has 3 joints but model 'arm4.xml' has 4", or
/// naming both models) otherwise.
void check_run_log(const RunLog& log, const mjModel* m, const std::string& model_path);

/// @brief The model's qpos at row `row` of a log that check_run_log accepted: the log's q on the
/// joints it has, the held joints where they were held.
void log_pose(const RunLog& log, std::size_t row, const mjModel* m, mjtNum* qpos);

}  // namespace idmpc::render
