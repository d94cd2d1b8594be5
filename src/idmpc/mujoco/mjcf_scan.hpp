#pragma once
/// @file mjcf_scan.hpp
/// @brief A light scan of an MJCF file (and the files it includes) before MuJoCo parses it:
/// elements with their attributes and line numbers, enough to bound texture sizes and to name
/// a missing asset file. Not an XML parser: comments, processing instructions and CDATA are
/// skipped, entities are not decoded.

#include <map>
#include <string>
#include <vector>

namespace idmpc::mj {

struct MjcfElement {
  std::string name;                               ///< e.g. "texture"
  std::map<std::string, std::string> attributes;  ///< as written
  std::string file;                               ///< the file it appears in
  int line = 0;                                   ///< 1-based
  /// @brief The attribute or `fallback` if absent.
  std::string get(const std::string& key, const std::string& fallback = "") const;
};

/// @brief Elements of `text` in document order.
std::vector<MjcfElement> scan_elements(const std::string& text, const std::string& file);

/// @brief Elements of the file at `path` and, in place of each `<include file="…"/>`, those of
/// the included file (resolved against the directory of `path`, up to 16 levels deep). Throws
/// std::runtime_error, one line naming the model and the include, for an include cycle, a file
/// included twice (MuJoCo includes each file once), and a file that is no input file
/// (input_file.hpp: missing, unreadable, a directory, FIFO or device, over 64 MiB) — before
/// reading it.
std::vector<MjcfElement> scan_mjcf(const std::string& path);

/// @brief An asset file an MJCF names: mesh, skin, height field or texture file.
struct AssetFile {
  std::string kind;      ///< "mesh", "texture", ...
  std::string resolved;  ///< path as MuJoCo 2.2 looks for it
  const MjcfElement* element = nullptr;
};

/// @brief The asset files of a scanned model, each resolved as MuJoCo 2.2 does: relative to
/// the model's directory joined with <compiler meshdir/texturedir> where given (or MuJoCo >= 2.3's
/// assetdir, which the translation of mjcf_translate.hpp turns into both).
std::vector<AssetFile> asset_files(const std::vector<MjcfElement>& elements, const std::string& model_path);

/// @brief Width and height of a PNG file from its header; false if it is no PNG or unreadable.
bool png_size(const std::string& path, long& width, long& height);

}  // namespace idmpc::mj
