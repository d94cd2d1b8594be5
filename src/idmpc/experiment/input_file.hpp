#pragma once
/// @file input_file.hpp
/// @brief Reading the files a user names (models and their includes, task files, trajectory
/// CSVs, run logs and summaries) without trusting them: only a regular file is opened for
/// reading (a directory, FIFO, device or socket is refused before anything is read, and a FIFO
/// never blocks the check), a file read whole is at most kMaxInputFileBytes, JSON is nested at
/// most kMaxJsonDepth levels, and a value echoed into an error message is abbreviated.

#include <cstdint>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace idmpc {

/// @brief The largest input file read whole: a model (or an include), a task file, a JSON file
/// or a trajectory CSV is never near this.
inline constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{64} << 20;  // 64 MiB
/// @brief The deepest nesting of JSON arrays and objects accepted: a task file has four levels.
inline constexpr int kMaxJsonDepth = 64;
/// @brief The longest file name a task or reference may give (Linux's PATH_MAX).
inline constexpr std::size_t kMaxPathChars = 4096;
/// @brief The longest value an error message shows in full (longer ones are abbreviated).
inline constexpr std::size_t kMaxShownChars = 80;

/// @brief `text` when at most `max_chars` bytes long, else its beginning (cut at a UTF-8
/// character boundary) followed by "…" and its length, e.g. "[[[[…" (120000 characters)".
std::string abbreviate(std::string_view text, std::size_t max_chars = kMaxShownChars);

/// @brief Whether `text` is a decimal number as users write them on the command line and in
/// task fields: (digits [. digits] | . digits) [e [sign] digits], no leading zero before another
/// digit (so no octal look-alike, no 0x, 0b or 0o prefix), with a leading sign if `sign`, and
/// also [sign] inf if `infinity`.
bool is_decimal_real(std::string_view text, bool sign, bool infinity);
/// @brief Whether `text` is [sign if `sign`] digits, no leading zero before another digit.
bool is_decimal_integer(std::string_view text, bool sign);

/// @brief Why `path` cannot be an input file of at most `max_bytes` bytes, or "" when it can:
/// "does not exist", "permission denied", "is a directory, expected <expected>", "is a FIFO,
/// expected <expected>" (likewise a device or a socket), "is 70 MiB, expected at most 64 MiB".
/// The file is opened without blocking (O_NONBLOCK: a FIFO without a writer does not hang)
/// and nothing is read. `expected` describes the file, e.g. "an MJCF or URDF file".
std::string input_file_problem(const std::string& path, const std::string& expected,
                               std::uintmax_t max_bytes = kMaxInputFileBytes);

/// @brief The whole file after the checks of input_file_problem (reading at most `max_bytes`);
/// throws std::invalid_argument "<noun> '<path>': <problem>", e.g. "task file 'd': is a
/// directory, expected a JSON file".
std::string read_input_file(const std::string& path, const std::string& noun, const std::string& expected,
                            std::uintmax_t max_bytes = kMaxInputFileBytes);

/// @brief JSON text parsed with its nesting bounded by kMaxJsonDepth (checked before parsing, so
/// that neither the parser nor the code walking the value recurses deeper); throws
/// std::invalid_argument "<where>: …" for a parse error, deeper nesting or a key given twice in
/// one object.
nlohmann::json parse_json(const std::string& text, const std::string& where);

/// @brief read_input_file (a JSON file) and parse_json; messages name "<noun> '<path>'".
nlohmann::json read_json_file(const std::string& path, const std::string& noun);

}  // namespace idmpc
