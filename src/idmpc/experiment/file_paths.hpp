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

}  // namespace idmpc
