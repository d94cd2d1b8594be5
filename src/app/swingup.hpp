#pragma once
/// @file swingup.hpp
/// @brief The paper's swing-up experiment (DESIGN §7) as used by `swingup` and `sweep`.

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "idmpc/mujoco/closed_loop.hpp"

namespace idmpc::app {

/// @brief Everything that defines one closed-loop run; the defaults are the paper's.
struct SwingupOptions {
  std::string model;
  std::string formulation = "id";
  std::string derivatives = "adjoint";
  int N = 25;
  int kmax = 10;
  double Tf = 0.5;
  double alpha = 1.0;
  double dt = 1e-3;
  double zeta = 0;  ///< 0 = 1/dt
  double h = 1e-8;
  double duration = 10.0;
  std::vector<double> q0;    ///< empty: (−π, 0, …, 0)
  std::vector<double> qref;  ///< empty: 0
  std::vector<double> Qq{1.0}, Qv{0.1}, Qa{0.0}, R{1e-4};
  bool direct_torque = false;
  bool simd_stages = true;  ///< ID + adjoint: evaluate stages in SIMD lanes
};

/// @brief Adds the swing-up options to a CLI sub-command.
void add_swingup_options(CLI::App& sub, SwingupOptions& opt);

/// @brief Outcome of one run with its summary (the JSON written by --summary).
struct SwingupOutcome {
  mj::RunResult result;
  nlohmann::json summary;
};

/// @brief Runs the experiment; streams the CSV log to `log_path` if non-empty (temporary file
/// renamed when the run ends, diverged or not). Throws on bad options before any output.
SwingupOutcome run_swingup(const SwingupOptions& opt, const std::string& log_path);

/// @brief Writes JSON to a file atomically.
void write_json(const nlohmann::json& j, const std::string& path);

/// @brief One-screen human summary of a run.
std::string human_summary(const nlohmann::json& s);

}  // namespace idmpc::app
