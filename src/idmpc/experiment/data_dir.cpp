#include "idmpc/experiment/data_dir.hpp"

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>

// the data directory relative to the executable's directory (the install's bindir → datadir)
#ifndef IDMPC_DATA_RELATIVE_DIR
#define IDMPC_DATA_RELATIVE_DIR "../share/idmpc"
#endif

namespace idmpc {
namespace {

namespace fs = std::filesystem;

constexpr const char* kHowToSet =
    "set IDMPC_DATA_DIR (idmpc: --data-dir) to the directory holding mjcf/ (an install's share/idmpc or the "
    "source tree)";

bool holds_mjcf(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir / "mjcf", ec);
}

// the setting of set_data_dir, shared by every thread of the process
struct Explicit {
  std::mutex mutex;
  std::string dir;
};

Explicit& explicit_setting() {
  static Explicit setting;
  return setting;
}

// the running executable's directory; empty where the system does not say
fs::path executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

}  // namespace

void set_data_dir(const std::string& dir) {
  if (!dir.empty() && !holds_mjcf(dir)) {
    throw std::invalid_argument("data directory '" + dir + "': expected a directory holding mjcf/ (an install's " +
                                "share/idmpc or the source tree), got none there");
  }
  Explicit& s = explicit_setting();
  const std::lock_guard<std::mutex> lock(s.mutex);
  s.dir = dir;
}

std::string data_dir() {
  // set in this process
  {
    Explicit& s = explicit_setting();
    const std::lock_guard<std::mutex> lock(s.mutex);
    if (!s.dir.empty()) return s.dir;
  }
  // set in the environment: used as given, so a wrong one is an error rather than a silent fallback
  if (const char* env = std::getenv(kDataDirVariable); env && *env) {
    if (!holds_mjcf(env)) {
      throw std::runtime_error(std::string(kDataDirVariable) + "='" + env +
                               "': expected a directory holding mjcf/, got none there; " + kHowToSet);
    }
    return env;
  }
  // beside the running executable: installed, or the build tree's link to the sources
  const fs::path exe_dir = executable_dir();
  const fs::path beside = exe_dir.empty() ? fs::path() : (exe_dir / IDMPC_DATA_RELATIVE_DIR).lexically_normal();
  if (!beside.empty() && holds_mjcf(beside)) return beside.string();
  throw std::runtime_error(std::string("idmpc data directory not found: ") + kDataDirVariable + " is not set and " +
                           (beside.empty() ? std::string("the executable's directory is unknown")
                                           : "'" + beside.string() + "' (beside the executable) has no mjcf/") +
                           "; " + kHowToSet);
}

std::string shipped_mjcf_path(const std::string& file) {
  // links resolved: the build tree's files are named by their place in the sources
  const fs::path mjcf = fs::path(data_dir()) / "mjcf";
  std::error_code ec;
  const fs::path resolved = fs::canonical(mjcf, ec);
  return ((ec ? mjcf : resolved) / file).string();
}

}  // namespace idmpc
