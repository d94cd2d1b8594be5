#pragma once
/// @file latency.hpp
/// @brief Compute latency in the closed loop (formulations.md §Compute latency): how long a control update takes before
/// its torque reaches the plant. `none` is the paper's timing (eqs. 27–28: every update's torque
/// is applied one control period after its measurement, however long it took); `measured` takes
/// each update's wall time; a fixed figure in ms simulates another CPU.

#include <string>

namespace idmpc {

struct Latency {
  enum class Kind { kNone, kMeasured, kFixed };
  Kind kind = Kind::kNone;
  double ms = 0;  ///< kFixed: the compute time of every update [ms]
  bool on() const { return kind != Kind::kNone; }
};

/// @brief "none", "measured" or a compute time in ms: a plain decimal number >= 0 ("2", "0.5",
/// "1e-1"; refused: "", "-1", "010", "0x1", "inf", "nan"). Throws std::invalid_argument "expected
/// none, measured or a compute time in ms (a finite decimal number >= 0), got '<text>'".
Latency parse_latency(const std::string& text);

/// @brief The text parse_latency reads back: "none", "measured" or the figure in ms.
std::string to_string(const Latency& latency);

}  // namespace idmpc
