#include "app/output_paths.hpp"

#include "idmpc/experiment/file_paths.hpp"
#include "idmpc/mujoco/mjcf_scan.hpp"

#include <nlohmann/json.hpp>

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace idmpc::app {
namespace {

namespace fs = std::filesystem;

std::string label(const NamedPath& p) { return p.option + " '" + p.path + "'"; }

// identity of a path: its inode if it exists, else its canonical spelling
struct Identity {
  bool exists = false;
  bool char_device = false;
  dev_t dev = 0;
  ino_t ino = 0;
  std::string canonical;
  bool same(const Identity& o) const {
    if (exists && o.exists) return dev == o.dev && ino == o.ino;
    return !exists && !o.exists && canonical == o.canonical;
  }
};

Identity identity(const std::string& path) {
  Identity id;
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    id.exists = true;
    id.char_device = S_ISCHR(st.st_mode);
    id.dev = st.st_dev;
    id.ino = st.st_ino;
    return id;
  }
  // absolute first: weakly_canonical leaves a relative path whose first component does not
  // exist as it is ("a.csv"), but makes "./a.csv" absolute
  std::error_code ec;
  const fs::path absolute = fs::absolute(follow_links(path), ec);
  const fs::path canonical = ec ? fs::path() : fs::weakly_canonical(absolute, ec);
  id.canonical = ec ? absolute.lexically_normal().string() : canonical.lexically_normal().string();
  return id;
}

}  // namespace

void check_output_paths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
  std::vector<std::pair<const NamedPath*, Identity>> seen;
  for (const NamedPath& in : inputs) {
    if (!in.path.empty()) seen.emplace_back(&in, identity(in.path));
  }
  const std::size_t n_inputs = seen.size();
  for (const NamedPath& out : outputs) {
    if (out.path.empty()) continue;
    std::error_code ec;
    if (fs::is_directory(out.path, ec)) {
      throw std::invalid_argument(label(out) + " is a directory: expected a file path");
    }
    const fs::path parent = fs::path(follow_links(out.path)).parent_path();
    if (!parent.empty() && !fs::is_directory(parent, ec)) {
      throw std::invalid_argument(label(out) + ": directory '" + parent.string() + "' does not exist");
    }
    const Identity id = identity(out.path);
    if (!id.char_device) {
      for (std::size_t k = 0; k < seen.size(); ++k) {
        if (!seen[k].second.same(id)) continue;
        if (k < n_inputs) {
          throw std::invalid_argument(label(out) + " is the same file as " + label(*seen[k].first) +
                                      ": expected an output that is not an input");
        }
        throw std::invalid_argument(label(out) + " and " + label(*seen[k].first) +
                                    " are the same file: expected a different file for each output");
      }
    }
    seen.emplace_back(&out, id);
  }
}

std::vector<NamedPath> model_inputs(const std::string& model, const std::string& option) {
  std::vector<NamedPath> inputs{{option, model}};
  if (model.empty()) return inputs;
  // a model that cannot be read or scanned is left to the loader to report
  try {
    const std::vector<mj::MjcfElement> elements = mj::scan_mjcf(model);
    std::set<std::string> listed{model};
    for (const mj::MjcfElement& e : elements) {
      if (listed.insert(e.file).second) inputs.push_back({option + "'s include", e.file});
    }
    for (const mj::AssetFile& a : mj::asset_files(elements, model)) {
      if (listed.insert(a.resolved).second) inputs.push_back({option + "'s " + a.kind, a.resolved});
    }
  } catch (const std::exception&) {
  }
  return inputs;
}

void check_utf8_paths(const std::vector<NamedPath>& paths, const std::string& why) {
  for (const NamedPath& p : paths) {
    try {
      (void)nlohmann::json(p.path).dump();
    } catch (const nlohmann::json::exception&) {
      std::string shown;  // the bytes that are no UTF-8 as \xNN
      for (const unsigned char c : p.path) {
        if (c < 0x80 && c >= 0x20) {
          shown += static_cast<char>(c);
        } else {
          static const char* hex = "0123456789ABCDEF";
          shown += std::string("\\x") + hex[c >> 4] + hex[c & 15];
        }
      }
      throw std::invalid_argument(p.option + " '" + shown + "': expected a UTF-8 file name (" + why + ")");
    }
  }
}

CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& value) { return value.empty() ? std::string("expected a file path, got ''") : std::string(); },
      "");
}

}  // namespace idmpc::app
