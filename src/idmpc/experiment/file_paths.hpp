#pragma once
/// @file file_paths.hpp
/// @brief Where a write to a path lands, shared by every output of the commands (logs,
/// summaries, sweep tables, videos).

#include <string>

namespace idmpc {

/// @brief The file a write to `path` lands in: symbolic links of its last component followed
/// (also a dangling one, whose target a write then creates); `path` itself if it is no link.
/// Throws std::runtime_error "cannot write 'path': …" for a loop of links.
std::string follow_links(const std::string& path);

/// @brief The name of a temporary file beside `target`: its directory joined with `prefix`,
/// the target's file name and `suffix` (e.g. "." and ".tmp.123.0.mp4" give
/// "dir/.v.mp4.tmp.123.0.mp4"). When that name would pass NAME_MAX (255 bytes), the target's
/// name is shortened, so that every valid output name has a temporary that fits.
std::string temporary_beside(const std::string& target, const std::string& prefix, const std::string& suffix);

}  // namespace idmpc
