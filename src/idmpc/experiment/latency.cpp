#include "idmpc/experiment/latency.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "idmpc/experiment/input_file.hpp"

namespace idmpc {

Latency parse_latency(const std::string& text) {
  if (text == "none") return {};
  if (text == "measured") return {Latency::Kind::kMeasured, 0};
  if (is_decimal_real(text, false, false)) {
    const double ms = std::strtod(text.c_str(), nullptr);
    if (std::isfinite(ms)) return {Latency::Kind::kFixed, ms};
  }
  throw std::invalid_argument("expected none, measured or a compute time in ms (a finite decimal number >= 0), got '" +
                              abbreviate(text) + "'");
}

std::string to_string(const Latency& latency) {
  switch (latency.kind) {
    case Latency::Kind::kNone:
      return "none";
    case Latency::Kind::kMeasured:
      return "measured";
    case Latency::Kind::kFixed:
      break;
  }
  // the shortest text that reads back as the same number
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, latency.ms).ptr;
  return std::string(buffer, end);
}

}  // namespace idmpc
