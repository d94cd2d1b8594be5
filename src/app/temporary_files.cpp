#include "app/temporary_files.hpp"

#include <climits>
#include <csignal>
#include <cstring>
#include <mutex>
#include <pthread.h>
#include <stdexcept>
#include <unistd.h>

#include <atomic>
#include <memory>

#ifdef IDMPC_HAVE_RENDER
#include "idmpc/render/video_writer.hpp"
#endif

namespace idmpc::app {
namespace {

// at most this many temporaries at once (a swingup holds two or three)
constexpr int kSlots = 32;
// every signal whose default action ends the process and that can be caught, except those of a
// fault of the process itself (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS): they
// keep their default (or a sanitizer's) handling and core dump
constexpr int kSignals[] = {SIGINT,  SIGTERM, SIGHUP,  SIGPIPE,   SIGQUIT, SIGUSR1, SIGUSR2, SIGXFSZ,
                            SIGXCPU, SIGALRM, SIGVTALRM, SIGPROF, SIGIO,   SIGPWR
#ifdef SIGSTKFLT
                            ,
                            SIGSTKFLT
#endif
};

enum SlotState : int { kFree = 0, kFilling = 1, kLive = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

// the registry: the handler can reach nothing but statics
Slot g_slots[kSlots];
// child processes writing temporaries (0: a free slot)
std::atomic<pid_t> g_children[kSlots];
static_assert(std::atomic<pid_t>::is_always_lock_free, "the signal handler needs lock-free atomics");

extern "C" void remove_temporaries_and_reraise(int sig) {
  // a child writing a temporary first, so that it cannot create it again
  for (std::atomic<pid_t>& child : g_children) {
    const pid_t pid = child.load();
    if (pid > 0) ::kill(pid, SIGKILL);
  }
  // unlink every live temporary; a slot being filled has no file yet
  for (Slot& s : g_slots) {
    if (s.state.load() == kLive) ::unlink(s.path);
  }
  // die of the same signal with its default action
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(sig, &dfl, nullptr);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, sig);
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
  raise(sig);
  _exit(128 + sig);
}

}  // namespace

void install_temporary_file_cleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_reraise;
    // a second signal waits until the first one's cleanup is done
    sigemptyset(&action.sa_mask);
    for (int sig : kSignals) sigaddset(&action.sa_mask, sig);
    action.sa_flags = SA_RESTART;
    for (int sig : kSignals) {
      struct sigaction old {};
      if (sigaction(sig, nullptr, &old) != 0) continue;
      if (old.sa_handler == SIG_IGN) continue;  // e.g. SIGINT of a background job
      sigaction(sig, &action, nullptr);
    }
#ifdef IDMPC_HAVE_RENDER
    render::set_temporary_registrar(
        [](const std::string& path) -> std::shared_ptr<void> { return std::make_shared<TemporaryFile>(path); },
        [](pid_t pid) -> std::shared_ptr<void> { return std::make_shared<ChildProcess>(pid); });
#endif
  });
}

TemporaryFile::TemporaryFile(const std::string& path) {
  if (path.size() >= PATH_MAX) {
    throw std::runtime_error("temporary path longer than PATH_MAX: '" + path + "'");
  }
  for (int k = 0; k < kSlots; ++k) {
    int expected = kFree;
    if (g_slots[k].state.compare_exchange_strong(expected, kFilling)) {
      std::memcpy(g_slots[k].path, path.c_str(), path.size() + 1);
      g_slots[k].state.store(kLive);
      slot_ = k;
      return;
    }
  }
  throw std::runtime_error("more than " + std::to_string(kSlots) +
                           " temporary files at once; cannot register '" + path + "'");
}

void TemporaryFile::release() {
  if (slot_ < 0) return;
  g_slots[slot_].state.store(kFree);
  slot_ = -1;
}

ChildProcess::ChildProcess(pid_t pid) {
  for (int k = 0; k < kSlots; ++k) {
    pid_t expected = 0;
    if (g_children[k].compare_exchange_strong(expected, pid)) {
      slot_ = k;
      return;
    }
  }
  throw std::runtime_error("more than " + std::to_string(kSlots) + " child processes at once");
}

ChildProcess::~ChildProcess() {
  if (slot_ >= 0) g_children[slot_].store(0);
}

int registered_temporary_files() {
  int live = 0;
  for (const Slot& s : g_slots) live += s.state.load() == kLive;
  return live;
}

}  // namespace idmpc::app
