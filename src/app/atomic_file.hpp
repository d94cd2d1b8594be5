#pragma once
/// @file atomic_file.hpp
/// @brief An output file written to a temporary name beside its target and renamed into place
/// on commit(), so that an error never leaves a half-written file.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace idmpc::app {

class AtomicFile {
 public:
  /// Opens the temporary file at once, so that an unwritable path fails before any work.
  explicit AtomicFile(std::string path) : path_(std::move(path)) {
    namespace fs = std::filesystem;
    const fs::path target(path_);
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(dir)) {
      throw std::runtime_error("cannot write '" + path_ + "': directory '" + dir.string() +
                               "' does not exist");
    }
    tmp_ = path_ + ".tmp." + std::to_string(::getpid());
    out_.open(tmp_);
    if (!out_) throw std::runtime_error("cannot write '" + path_ + "': permission denied or bad path");
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() {
    if (!committed_) {
      out_.close();
      std::remove(tmp_.c_str());
    }
  }
  std::ofstream& stream() { return out_; }
  const std::string& path() const { return path_; }
  /// @brief Flushes and renames the temporary file onto the target.
  void commit() {
    out_.close();
    if (!out_ || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
      std::remove(tmp_.c_str());
      throw std::runtime_error("cannot write '" + path_ + "'");
    }
    committed_ = true;
  }

 private:
  std::string path_, tmp_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace idmpc::app
