#pragma once
/// @file atomic_file.hpp
/// @brief An output file written to a temporary name beside its target and renamed into place
/// on commit(), so that an error never leaves a half-written file.
///
/// - A regular target (or a new one) is written to the hidden `.<name>.tmp.<pid>.<k>` in the
///   target's directory (the name shortened where it would pass NAME_MAX) and renamed onto it
///   by commit(). An existing target keeps its permission bits
///   (and, as root, its owner). The temporary is registered for removal when a signal ends the process
///   (temporary_files.hpp) and removed by the destructor if commit() was never reached.
/// - A symbolic link is followed: the temporary goes beside the link's final target and is
///   renamed onto that target, so the link stays a link.
/// - A special file (character device such as /dev/null, FIFO, socket) is never replaced: it is
///   written through directly. A FIFO is opened on the first call of stream(), so that merely
///   constructing an AtomicFile (to check a path early) does not send end-of-file to a reader.
/// - A directory is refused.
/// Every failure names the path and the reason (strerror), e.g. "No space left on device".

#include <memory>
#include <ostream>
#include <string>

#include "app/temporary_files.hpp"

namespace idmpc::app {

class FdStreamBuf;

class AtomicFile {
 public:
  /// Creates the temporary file at once (or opens a non-FIFO special file), so that an
  /// unwritable path fails before any work.
  /// @throws std::runtime_error naming the path and the reason
  explicit AtomicFile(std::string path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicFile();

  /// @brief The stream to write to. Write errors are kept and reported by commit().
  /// @throws std::runtime_error if a FIFO target cannot be opened
  std::ostream& stream();
  /// @brief The path as given.
  const std::string& path() const { return path_; }
  /// @brief True if the target is a special file written through directly.
  bool direct() const { return direct_; }
  /// @brief Flushes, syncs and renames the temporary file onto the target (or, for a special
  /// file, flushes and closes it).
  /// @throws std::runtime_error naming the path and the reason if any write, the sync, the
  /// close or the rename failed; the temporary is removed and the target left as it was.
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what, int err);
  void open_direct();
  void discard();

  std::string path_;    // as given
  std::string target_;  // the file that is replaced (links resolved) or written through
  std::string tmp_;
  bool direct_ = false;
  bool committed_ = false;
  int fd_ = -1;
  std::unique_ptr<FdStreamBuf> buf_;
  std::unique_ptr<std::ostream> out_;
  std::unique_ptr<TemporaryFile> registration_;
};

/// @brief A file that grows by whole pieces: each append() is written and synced, or, if any
/// write or the sync fails (a full disk, a file size limit), the file is cut back to its length
/// before it, so that it never ends in half a piece.
class AppendFile {
 public:
  /// Opens an existing file for appending.
  /// @throws std::runtime_error naming the path and the reason
  explicit AppendFile(std::string path);
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;
  ~AppendFile();
  /// @throws std::runtime_error "cannot write 'path': File too large" (strerror of the failure)
  void append(const std::string& text);

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace idmpc::app
