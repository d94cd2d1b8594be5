#pragma once
/// @file trajectory_io.hpp
/// @brief Moving references from data: a planner's CSV of samples, and the "reference" object of
/// a task file (docs/tasks.md) describing a circle, a line, waypoints or a CSV file.

#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "idmpc/ocp/trajectory.hpp"

namespace idmpc {

/// @brief Samples from a CSV file: each row is a time [s] then `dim` values, times strictly
/// increasing, at least 2 rows. An optional header (a first line in which no field is a number,
/// with 1 + dim columns), blank lines and comments (from '#' to the end of the line) are skipped. Numbers are parsed strictly: decimal or scientific, optional sign, spaces around
/// them allowed, nothing else. Throws std::invalid_argument with one line naming the file, line
/// and column and the bad text (not a number, not finite, wrong column count, times not
/// increasing, too few rows, unreadable file).
SampledTrajectory read_trajectory_csv(const std::string& path, int dim);

/// @brief A moving reference from its JSON object, {"shape": "circle" | "line" | "waypoints" |
/// "csv", …} (fields, defaults and units in docs/tasks.md). `start` is the reference's value at
/// t = 0 (its size is the trajectory's dim; e.g. the end effector's start position); `where`
/// names the source in messages (e.g. "task 'a.json' field 'reference'"); a "csv" file is found
/// relative to `base_dir`. Throws std::invalid_argument with one line naming `where` and the
/// field, also for an unknown field or a value of the wrong dimension.
///
/// `plane_normal`, when given, is the normal of the only plane the reference can move in (a
/// planar arm's end effector): a circle without `normal`, or with `"normal": "facing"`, lies in
/// that plane. `outward`, when given, is the direction the reference cannot go at the start (an
/// arm stretched out at a singular pose: from its base out through the start): a circle without
/// `center` then has the start as its point farthest along it (where it lies mostly in the
/// circle's plane), so that the circle lies on the side the arm can reach.
std::unique_ptr<Trajectory> trajectory_from_json(const nlohmann::json& j, const std::string& where,
                                                 const VecX<double>& start, const std::string& base_dir,
                                                 const std::optional<Vec3<double>>& plane_normal = std::nullopt,
                                                 const std::optional<Vec3<double>>& outward = std::nullopt);

}  // namespace idmpc
