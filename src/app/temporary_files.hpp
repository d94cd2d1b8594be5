#pragma once
/// @file temporary_files.hpp
/// @brief Temporary files removed when the process is interrupted.
///
/// Every temporary file the command line creates (AtomicFile's `<target>.tmp.<pid>.<k>`, a
/// video's temporary log, the renderer's temporary video and ffmpeg's log, ...) is registered
/// here for as long as it exists. main() calls install_temporary_file_cleanup() once; on a
/// signal that ends the process (SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGQUIT, SIGUSR1, SIGUSR2,
/// SIGXFSZ, SIGXCPU, SIGALRM, SIGVTALRM, SIGPROF, SIGIO, SIGPWR, SIGSTKFLT) the handler unlinks
/// every registered path and then re-raises the signal with its default action, so the process
/// ends as it would have without the handler (the shell reports 128 + signal number; SIGQUIT,
/// SIGXFSZ and SIGXCPU still dump core where cores are enabled). Not handled: SIGKILL and
/// SIGSTOP (they cannot be caught) and the signals of a fault of the process itself (SIGSEGV,
/// SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS), left to their default or a sanitizer.
///
/// The registry is the one piece of global mutable state of the command line: a signal handler
/// can reach nothing else. It is a fixed array of slots (no allocation, no locks); the handler
/// uses only async-signal-safe calls (unlink, sigaction, sigprocmask, raise, _exit).

#include <string>

#include <sys/types.h>

namespace idmpc::app {

/// @brief Installs the cleanup handler for the signals above (idempotent), and has the renderer
/// (where built) register its temporaries here. A signal that was ignored when the process
/// started (e.g. SIGINT under `nohup … &`, SIGXFSZ to get EFBIG errors instead) stays ignored.
void install_temporary_file_cleanup();

/// @brief Registers a path (to be) created as a temporary for the lifetime of this object.
/// Register before creating the file, so that no moment exists in which the file is there but
/// unknown to the handler.
/// @throws std::runtime_error if the path is longer than PATH_MAX or every slot is taken
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& path);
  ~TemporaryFile() { release(); }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  /// @brief Forgets the path (after the file was renamed or removed).
  void release();

 private:
  int slot_ = -1;
};

/// @brief Registers a child process that writes a temporary (ffmpeg writing a video) for the
/// lifetime of this object: the handler kills it (SIGKILL) before it removes the temporaries,
/// so that the child cannot create a file again once they are gone.
/// @throws std::runtime_error if every slot is taken
class ChildProcess {
 public:
  explicit ChildProcess(pid_t pid);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

 private:
  int slot_ = -1;
};

/// @brief Number of temporaries registered now; for tests.
int registered_temporary_files();

}  // namespace idmpc::app
