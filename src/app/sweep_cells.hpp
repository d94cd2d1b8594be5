#pragma once
/// @file sweep_cells.hpp
/// @brief A sweep as independent cells: the cells' IDs, their records in the output directory,
/// and the lock that keeps a serial sweep or a merge apart from cell runs.
///
/// The machinery knows a cell only by its resume key (every axis and setting the cell runs
/// with): a new axis of the grid changes the keys, never this code.
///
/// - A cell's ID is the hash of its key: the same options give the same IDs on every run and
///   machine, and other options give other IDs.
/// - A cell run writes its record, `<out>/cells/<ID>.csv`, through a temporary renamed into
///   place (AtomicFile), so that a reader sees a whole record or none.
/// - The output directory's lock (flock) is taken shared by cell runs, which may run side by
///   side, and exclusive by a serial sweep and by a merge, which write the tables. On a shared
///   network directory the lock holds between the processes of one host only.

#include <regex>
#include <string>

namespace idmpc::app {

/// @brief The ID of a cell: the 16 hex digits of the FNV-1a hash of its resume key.
std::string cell_id(const std::string& key);

/// @brief The record of the cell `id` of a sweep writing into `out_dir`: `<out_dir>/cells/<id>.csv`.
std::string cell_record_path(const std::string& out_dir, const std::string& id);

/// @brief The lock of a sweep's output directory, held for the object's lifetime (and released
/// however the process ends).
class OutputDirectoryLock {
 public:
  enum class Mode { exclusive, shared };
  /// Locks the existing directory `dir` without waiting.
  /// @throws std::runtime_error naming the directory if it cannot be opened, or if another
  /// process holds the lock in a conflicting mode
  OutputDirectoryLock(const std::string& dir, Mode mode);
  ~OutputDirectoryLock();
  OutputDirectoryLock(const OutputDirectoryLock&) = delete;
  OutputDirectoryLock& operator=(const OutputDirectoryLock&) = delete;

 private:
  int fd_ = -1;
};

/// @brief Removes the files of `dir` whose names match `name` — a pattern whose first group is
/// the process ID of an AtomicFile's temporary (`.<name>.tmp.<pid>.<k>`) — and whose process is
/// gone: the temporaries of a killed run. Files of live processes are kept.
void remove_stale_temporaries(const std::string& dir, const std::regex& name);

}  // namespace idmpc::app
