#include "app/sweep_cells.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include "idmpc/experiment/run_record.hpp"

namespace idmpc::app {

std::string cell_id(const std::string& key) {
  // text_hash is "fnv1a64:<16 hex digits>"; the digits alone make a file name and a shell word
  const std::string hash = text_hash(key);
  return hash.substr(hash.find(':') + 1);
}

std::string cell_record_path(const std::string& out_dir, const std::string& id) {
  return (std::filesystem::path(out_dir) / "cells" / (id + ".csv")).string();
}

OutputDirectoryLock::OutputDirectoryLock(const std::string& dir, Mode mode) {
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error("cannot open --out '" + dir + "': " + std::strerror(errno));
  if (::flock(fd_, (mode == Mode::shared ? LOCK_SH : LOCK_EX) | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd_);
    if (err != EWOULDBLOCK) throw std::runtime_error("cannot lock --out '" + dir + "': " + std::strerror(err));
    // a serial sweep or a merge excludes everything; cells exclude a serial sweep and a merge
    throw std::runtime_error(mode == Mode::shared
                                 ? "another sweep is writing into '" + dir +
                                       "' (it is locked by a serial sweep or a merge); wait for it or use another --out"
                                 : "another sweep is writing into '" + dir +
                                       "' (it is locked by a sweep or by cells running there); wait for it or use "
                                       "another --out");
  }
}

OutputDirectoryLock::~OutputDirectoryLock() { ::close(fd_); }

void remove_stale_temporaries(const std::string& dir, const std::regex& name) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string file = entry.path().filename().string();
    std::smatch m;
    if (!std::regex_match(file, m, name) || !entry.is_regular_file(ec)) continue;
    const long pid = std::strtol(m[1].str().c_str(), nullptr, 10);
    const bool gone = pid > 0 && pid != ::getpid() && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
    if (gone) std::filesystem::remove(entry.path(), ec);
  }
}

}  // namespace idmpc::app
