#include "idmpc/experiment/latency.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "idmpc/experiment/input_file.hpp"

namespace idmpc {
namespace {

// decimal digits from `i`; how many
std::size_t digits(const std::string& s, std::size_t& i) {
  const std::size_t begin = i;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
  return i - begin;
}

// digits [. digits] | . digits, [e [sign] digits], without a leading zero before other digits
// (the command line's rule for numbers, app/number_options.hpp, without a sign)
bool plain_decimal(const std::string& s) {
  std::size_t i = 0;
  const std::size_t whole = digits(s, i);
  if (whole > 1 && s[0] == '0') return false;
  std::size_t fraction = 0;
  if (i < s.size() && s[i] == '.') {
    ++i;
    fraction = digits(s, i);
  }
  if (whole + fraction == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
    if (digits(s, i) == 0) return false;
  }
  return i == s.size();
}

}  // namespace

Latency parse_latency(const std::string& text) {
  if (text == "none") return {};
  if (text == "measured") return {Latency::Kind::kMeasured, 0};
  if (plain_decimal(text)) {
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
