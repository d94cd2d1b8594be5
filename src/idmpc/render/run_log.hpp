#pragma once
/// @file run_log.hpp
/// @brief Closed-loop run logs (the CSV written by `idmpc swingup`) read back for replay.

#include <cstddef>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

namespace idmpc::render {

/// @brief One closed-loop run: per control step the time, the plant's q, the applied torque u,
/// the optimality residual and the controller's update time.
///
/// CSV header: `t,q0..q{n-1},v0..v{n-1},u0..u{n-1},residual,update_ms`; v is checked but not
/// kept. Values may be nan/inf (a diverged run); the renderer holds the last finite pose.
struct RunLog {
  std::string path;   ///< the CSV file it was read from
  std::string label;  ///< e.g. "C/GMRES (ID, adjoint) N=25 kmax=10", or the file's stem
  std::string formulation;  ///< "fd" / "id" from the JSON summary, or ""
  std::string derivatives;  ///< "matrix" / "adjoint" / ... from the JSON summary, or ""
  int n = 0;          ///< joints (columns q0..q{n-1})
  int nu = 0;         ///< torque columns u0..u{nu-1} (n for the fully actuated arms)
  std::vector<double> t;          ///< rows
  std::vector<double> q;          ///< rows x n, row-major
  std::vector<double> u;          ///< rows x nu, row-major
  std::vector<double> residual;   ///< rows
  std::vector<double> update_ms;  ///< rows

  std::size_t rows() const { return t.size(); }
  const double* q_row(std::size_t i) const { return q.data() + i * static_cast<std::size_t>(n); }
  const double* u_row(std::size_t i) const { return u.data() + i * static_cast<std::size_t>(nu); }
  /// @brief Euclidean norm of u in row i.
  double u_norm(std::size_t i) const;
  /// @brief Index of the row whose time is nearest to `time` (rows() must be > 0).
  std::size_t nearest_row(double time) const;
  /// @brief Whether q of row i is finite.
  bool finite_pose(std::size_t i) const;
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front(); }
};

/// @brief Reads a run log CSV and, when `<same path>.json` exists beside it, its summary
/// (fields formulation, derivatives, N, kmax) for the label. Throws std::runtime_error naming
/// the file (and the line number) for a missing or unreadable file, a bad header, a row with
/// the wrong number of columns, a non-numeric value, non-increasing times, no rows at all, or a
/// malformed JSON summary.
RunLog read_run_log(const std::string& csv_path);

/// @brief Checks that a log fits a model: its joint count equals the model's nq. Throws
/// std::invalid_argument ("log 'x.csv' has 3 joints but model 'arm4.xml' has 4") otherwise.
void check_run_log(const RunLog& log, const mjModel* m, const std::string& model_path);

}  // namespace idmpc::render
