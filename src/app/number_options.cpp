#include "app/number_options.hpp"

#include <cctype>
#include <string>

#include "idmpc/experiment/input_file.hpp"

namespace idmpc::app {
namespace {

// decimal digits from `i`; how many
std::size_t digits(const std::string& s, std::size_t& i) {
  const std::size_t begin = i;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
  return i - begin;
}

// [sign] digits, without a leading zero before another digit
bool decimal_integer(const std::string& s, bool sign) {
  std::size_t i = 0;
  if (sign && i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  const std::size_t first = i;
  const std::size_t n = digits(s, i);
  return n > 0 && i == s.size() && !(n > 1 && s[first] == '0');
}

// [sign] (digits [. digits] | . digits) [e [sign] digits], or [sign] inf
bool decimal_real(const std::string& s) {
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  if (s.compare(i, std::string::npos, "inf") == 0) return true;
  const std::size_t first = i;
  const std::size_t whole = digits(s, i);
  if (whole > 1 && s[first] == '0') return false;
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

void require_decimal_numbers(CLI::App& command) {
  for (CLI::Option* option : command.get_options()) {
    const std::string type = option->get_type_name();
    const bool is_unsigned = type.rfind("UINT", 0) == 0;
    const bool is_integer = is_unsigned || type.rfind("INT", 0) == 0;
    if (!is_integer && type.rfind("FLOAT", 0) != 0) continue;
    // an empty description leaves the option's help as it is
    option->check(CLI::Validator(
        [is_integer, is_unsigned](std::string& value) -> std::string {
          const bool ok = is_integer ? decimal_integer(value, !is_unsigned) : decimal_real(value);
          if (ok) return "";
          const std::string expected =
              is_unsigned ? "a decimal integer >= 0 such as 10 (no leading zero, no 0x, 0b or 0o prefix)"
              : is_integer ? "a decimal integer such as 10 (no leading zero, no 0x, 0b or 0o prefix)"
                           : "a decimal number such as 0.5, -2 or 1e-3 (no leading zero)";
          return "expected " + expected + ", got '" + abbreviate(value) + "'";
        },
        ""));
  }
}

}  // namespace idmpc::app
