#include "app/number_options.hpp"

#include <string>

#include "idmpc/experiment/input_file.hpp"

namespace idmpc::app {

void require_decimal_numbers(CLI::App& command) {
  for (CLI::Option* option : command.get_options()) {
    const std::string type = option->get_type_name();
    const bool is_unsigned = type.rfind("UINT", 0) == 0;
    const bool is_integer = is_unsigned || type.rfind("INT", 0) == 0;
    if (!is_integer && type.rfind("FLOAT", 0) != 0) continue;
    // an empty description leaves the option's help as it is
    option->check(CLI::Validator(
        [is_integer, is_unsigned](std::string& value) -> std::string {
          const bool ok = is_integer ? is_decimal_integer(value, !is_unsigned) : is_decimal_real(value, true, true);
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
