#include "idmpc/experiment/file_paths.hpp"

#include <sys/stat.h>

#include <climits>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace idmpc {

std::string follow_links(const std::string& path) {
  namespace fs = std::filesystem;
  fs::path p(path);
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return p.string();
    std::error_code ec;
    const fs::path link = fs::read_symlink(p, ec);
    if (ec) return p.string();
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  throw std::runtime_error("cannot write '" + path + "': " + std::strerror(ELOOP));
}

std::string temporary_beside(const std::string& target, const std::string& prefix, const std::string& suffix) {
  namespace fs = std::filesystem;
  const fs::path t(target);
  std::string name = t.filename().string();
  const std::size_t room = NAME_MAX > prefix.size() + suffix.size() ? NAME_MAX - prefix.size() - suffix.size() : 0;
  if (name.size() > room) name.resize(room);
  return (t.parent_path() / (prefix + name + suffix)).string();
}

}  // namespace idmpc
