#pragma once
/// @file number_options.hpp
/// @brief One rule for every numeric command-line option: a plain decimal number, nothing a
/// user could mean otherwise. CLI11 would read "010" as octal 8, "0x10" as 16 and "" as 0.
///   integers (N, kmax, seed, width, …): an optional sign and decimal digits without a leading
///   zero: "0", "25", "-2"; refused: "", "010", "0x10", "0b1", "0o7", "1e3", "2.0"
///   reals (Tf, alpha, weights, …): an optional sign, decimal digits with an optional fraction
///   and exponent, without a leading zero before other digits, or inf: "0", "0.5", ".5", "-2",
///   "1e-3", "inf"; refused: "", "010", "00.5", "0x1p3", "nan", "1,5"
/// A refused value is one error line naming the option and the value.

#include <CLI/CLI.hpp>

namespace idmpc::app {

/// @brief Applies the rule to every option of `command` that takes numbers (CLI11 type INT,
/// UINT or FLOAT, one value or several): call it once the command's options are declared.
void require_decimal_numbers(CLI::App& command);

}  // namespace idmpc::app
