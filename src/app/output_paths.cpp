#include "app/output_paths.hpp"

#include "idmpc/experiment/file_paths.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
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
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(follow_links(path), ec);
  id.canonical = ec ? fs::absolute(path).lexically_normal().string() : canonical.string();
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

}  // namespace idmpc::app
