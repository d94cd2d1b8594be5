#include "idmpc/render/video_writer.hpp"

#include "idmpc/experiment/file_paths.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace idmpc::render {
namespace {

TemporaryRegistrar& registrar() {
  static TemporaryRegistrar r;
  return r;
}
ChildRegistrar& child_registrar() {
  static ChildRegistrar r;
  return r;
}

// the registration of a temporary, or none (a registrar that cannot take it)
std::shared_ptr<void> register_temporary(const std::string& path) noexcept {
  try {
    return registrar() ? registrar()(path) : nullptr;
  } catch (...) {
    return nullptr;
  }
}

// creates a new file `prefix + name + ".tmp.<pid>.<k>" + suffix` beside `target` (shortened to fit
// NAME_MAX), registered before it exists; errno is kept on failure (-1)
int create_temporary(const std::string& target, const std::string& prefix, const std::string& suffix,
                     std::string& path, std::shared_ptr<void>& guard) {
  static std::atomic<unsigned> counter{0};
  for (;;) {
    path = temporary_beside(target, prefix, ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++) + suffix);
    guard = register_temporary(path);
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd >= 0) return fd;
    const int err = errno;
    guard.reset();
    path.clear();
    if (err != EEXIST) {
      errno = err;
      return -1;
    }
  }
}

// Why the MP4 at `path` is not a complete file, or "" if it is: its top-level boxes must tile
// the file exactly and include the movie header (moov) and the media data (mdat). ffmpeg exits
// 0 when its writes fail (a full disk, a file size limit) and leaves a truncated file.
std::string mp4_incomplete(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot be read back";
  in.seekg(0, std::ios::end);
  const long long size = static_cast<long long>(in.tellg());
  in.seekg(0);
  bool moov = false, mdat = false;
  long long at = 0;
  while (at < size) {
    unsigned char h[16];
    if (size - at < 8 || !in.read(reinterpret_cast<char*>(h), 8)) return "a box header is cut off at byte " + std::to_string(at);
    long long box = (static_cast<long long>(h[0]) << 24) | (h[1] << 16) | (h[2] << 8) | h[3];
    const std::string type(reinterpret_cast<const char*>(h + 4), 4);
    if (box == 1) {
      if (!in.read(reinterpret_cast<char*>(h + 8), 8)) return "a box header is cut off at byte " + std::to_string(at);
      box = 0;
      for (int k = 8; k < 16; ++k) box = (box << 8) | h[k];
    } else if (box == 0) {
      box = size - at;  // to the end of the file
    }
    if (box < 8 || at + box > size) {
      return "box '" + type + "' at byte " + std::to_string(at) + " needs " + std::to_string(box) + " bytes, " +
             std::to_string(size - at) + " are there";
    }
    moov = moov || type == "moov";
    mdat = mdat || type == "mdat";
    at += box;
    in.seekg(at);
  }
  if (!moov) return "it has no movie header (moov)";
  if (!mdat) return "it has no media data (mdat)";
  return "";
}

constexpr std::size_t kStderrTailChars = 1500;  // enough for ffmpeg's last few error lines

std::string errno_text(int err) { return std::strerror(err); }

// the last lines of a text file, trimmed to at most kStderrTailChars
std::string file_tail(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) {
    text.pop_back();
  }
  if (text.size() > kStderrTailChars) {
    text = text.substr(text.size() - kStderrTailChars);
    const auto nl = text.find('\n');
    if (nl != std::string::npos) text = text.substr(nl + 1);
    text = "..." + text;
  }
  return text;
}

std::string describe_status(int status) {
  if (WIFEXITED(status)) return "exit status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "wait status " + std::to_string(status);
}

// writes all bytes to a pipe; false (errno set) if the reader is gone or another error occurs.
// SIGPIPE is blocked for the write and a SIGPIPE it raised is consumed, so a dead ffmpeg is an
// error instead of killing the process
bool write_all(int fd, const unsigned char* data, std::size_t size) {
  sigset_t pipe_set;
  sigset_t old_set;
  sigemptyset(&pipe_set);
  sigaddset(&pipe_set, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_set, &old_set);
  sigset_t pending;
  sigpending(&pending);
  const bool was_pending = sigismember(&pending, SIGPIPE) == 1;

  bool ok = true;
  int saved_errno = 0;
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      ok = false;
      saved_errno = errno;
      break;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  if (!ok && saved_errno == EPIPE && !was_pending) {
    const timespec zero{0, 0};
    while (sigtimedwait(&pipe_set, nullptr, &zero) == -1 && errno == EINTR) {
    }
  }
  pthread_sigmask(SIG_SETMASK, &old_set, nullptr);
  errno = saved_errno;
  return ok;
}

// a device, FIFO or socket: written through, never replaced
bool is_special(const struct stat& st) { return !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode); }

std::string format_fps(double fps) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.9g", fps);
  return text;
}

}  // namespace

void set_temporary_registrar(TemporaryRegistrar files, ChildRegistrar children) {
  registrar() = std::move(files);
  child_registrar() = std::move(children);
}

std::string find_on_path(const std::string& name) {
  if (name.find('/') != std::string::npos) {
    return access(name.c_str(), X_OK) == 0 ? name : "";
  }
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/local/bin:/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + name;
    struct stat st {};
    if (stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
        access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
  }
  return "";
}

void check_output_writable(const std::string& path) {
  namespace fs = std::filesystem;
  if (path.empty()) throw std::invalid_argument("output path: expected a file name, got ''");
  const std::string head = "cannot write '" + path + "': ";
  const std::string target = follow_links(path);
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0 && is_special(st)) {
    if (::access(target.c_str(), W_OK) != 0) throw std::runtime_error(head + errno_text(errno));
    return;
  }
  const fs::path out(target);
  const fs::path dir = out.has_parent_path() ? out.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    throw std::runtime_error(head + "directory '" + dir.string() + "' does not exist");
  }
  if (!fs::is_directory(dir, ec)) {
    throw std::runtime_error(head + "'" + dir.string() + "' is not a directory");
  }
  if (fs::is_directory(out, ec)) {
    throw std::runtime_error(head + "expected a file name, got a directory");
  }

  // the only reliable test (root, read-only mounts, /proc) is to create a file there
  std::string probe;
  std::shared_ptr<void> guard;
  const int fd = create_temporary((dir / "idmpc-write-test").string(), ".", "", probe, guard);
  if (fd < 0) {
    const int err = errno;
    throw std::runtime_error(head + "directory '" + dir.string() + "' is not writable (" +
                             errno_text(err) + ")");
  }
  close(fd);
  std::remove(probe.c_str());
}

VideoWriter::VideoWriter(const std::string& out_mp4, int width, int height, double fps)
    : out_path_(out_mp4), width_(width), height_(height) {
  namespace fs = std::filesystem;
  if (width < 2 || height < 2 || width % 2 != 0 || height % 2 != 0) {
    throw std::invalid_argument("video size: expected positive even width and height (H.264 "
                                "yuv420p), got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (!(fps > 0) || fps > 1000) {
    throw std::invalid_argument("video frame rate: expected 0 < fps <= 1000, got " +
                                format_fps(fps));
  }
  const std::string ffmpeg = find_on_path("ffmpeg");
  if (ffmpeg.empty()) {
    throw std::runtime_error("ffmpeg not found on PATH: install the Debian package ffmpeg");
  }
  check_output_writable(out_mp4);

  // a link is followed (the link stays), a special file written through, an existing file's
  // permissions kept
  target_path_ = follow_links(out_mp4);
  struct stat st {};
  if (::stat(target_path_.c_str(), &st) == 0) {
    if (is_special(st)) {
      direct_ = true;
    } else {
      existing_mode_ = static_cast<int>(st.st_mode & 07777);
      existing_uid_ = st.st_uid;
      existing_gid_ = st.st_gid;
    }
  }

  // temporary video next to the output, so the final rename stays on one file system (for a
  // special file, in the temporary directory: its bytes are copied into it)
  const fs::path out(target_path_);
  const fs::path dir = direct_ ? fs::temp_directory_path()
                               : (out.has_parent_path() ? out.parent_path() : fs::path("."));
  const int tmp_fd =
      create_temporary((dir / out.filename()).string(), ".", ".mp4", tmp_path_, tmp_guard_);
  if (tmp_fd < 0) {
    const int err = errno;
    throw std::runtime_error("cannot write video '" + out_mp4 + "': expected a writable "
                             "directory '" + dir.string() + "', got: " + errno_text(err));
  }
  close(tmp_fd);

  // ffmpeg's stderr goes to a temporary log
  const int log_fd = create_temporary((fs::temp_directory_path() / "idmpc-ffmpeg").string(), "",
                                      ".log", log_path_, log_guard_);
  if (log_fd < 0) {
    const int err = errno;
    std::remove(tmp_path_.c_str());
    tmp_guard_.reset();
    throw std::runtime_error("cannot create a temporary log file for ffmpeg in '" +
                             fs::temp_directory_path().string() + "': " + errno_text(err));
  }

  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    const int err = errno;
    close(log_fd);
    abandon();
    throw std::runtime_error("cannot create a pipe to ffmpeg: " + errno_text(err));
  }

  // raw rgb24 frames on stdin -> H.264 yuv420p MP4
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  const std::string rate = format_fps(fps);
  std::vector<std::string> args = {ffmpeg,       "-hide_banner", "-nostats",  "-loglevel",
                                   "error",      "-y",           "-f",        "rawvideo",
                                   "-pix_fmt",   "rgb24",        "-s",        size,
                                   "-framerate", rate,           "-i",        "pipe:0",
                                   "-an",        "-c:v",         "libx264",   "-preset",
                                   "medium",     "-crf",         "18",        "-pix_fmt",
                                   "yuv420p",    "-movflags",    "+faststart", "-f",
                                   "mp4",        tmp_path_};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, log_fd, STDERR_FILENO);
  const int rc = posix_spawn(&pid_, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[0]);
  close(log_fd);
  if (rc != 0) {
    close(fds[1]);
    pid_ = -1;
    abandon();
    throw std::runtime_error("cannot start '" + ffmpeg + "': " + errno_text(rc));
  }
  pipe_fd_ = fds[1];
  try {
    if (child_registrar()) child_guard_ = child_registrar()(pid_);
  } catch (...) {
    // unregistered: a signal leaves ffmpeg to end when its input closes
  }
}

VideoWriter::~VideoWriter() {
  if (!finished_) abandon();
}

void VideoWriter::write_frame(const unsigned char* rgb) {
  if (finished_ || pipe_fd_ < 0) {
    throw std::logic_error("VideoWriter::write_frame after finish()");
  }
  const std::size_t bytes =
      static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3;
  if (!write_all(pipe_fd_, rgb, bytes)) {
    const int err = errno;
    fail_with_ffmpeg_status("ffmpeg stopped reading frame " + std::to_string(frames_) + " (" +
                            errno_text(err) + ")");
  }
  ++frames_;
}

void VideoWriter::finish() {
  if (finished_) return;
  close(pipe_fd_);
  pipe_fd_ = -1;
  const int status = wait_for_ffmpeg();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string tail = file_tail(log_path_);
    abandon();
    throw std::runtime_error("ffmpeg failed to encode '" + out_path_ +
                             "': expected exit status 0, got " + describe_status(status) +
                             (tail.empty() ? std::string() : "; ffmpeg said: " + tail));
  }
  if (const std::string why = mp4_incomplete(tmp_path_); !why.empty()) {
    const std::string tail = file_tail(log_path_);
    abandon();
    throw std::runtime_error("ffmpeg exited 0 but the video for '" + out_path_ + "' is incomplete (" + why +
                             "; a full disk or a file size limit?); nothing was replaced" +
                             (tail.empty() ? std::string() : "; ffmpeg said: " + tail));
  }
  if (direct_) {
    copy_into_target();
    std::remove(tmp_path_.c_str());
    std::remove(log_path_.c_str());
    tmp_guard_.reset();
    log_guard_.reset();
    finished_ = true;
    return;
  }
  // the temporary was made 0600: the video keeps the permissions (and, as root, the owner) of
  // the file it replaces, or gets those of a normally created file
  if (existing_mode_ >= 0) {
    if (::geteuid() == 0 && ::chown(tmp_path_.c_str(), existing_uid_, existing_gid_) != 0) {
      // best effort: a filesystem without owners keeps ours
    }
    ::chmod(tmp_path_.c_str(), static_cast<mode_t>(existing_mode_));
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::chmod(tmp_path_.c_str(), 0666 & ~mask);
  }
  if (std::rename(tmp_path_.c_str(), target_path_.c_str()) != 0) {
    const int err = errno;
    abandon();
    throw std::runtime_error("cannot move the encoded video to '" + out_path_ +
                             "': " + errno_text(err));
  }
  tmp_guard_.reset();
  std::remove(log_path_.c_str());
  log_guard_.reset();
  finished_ = true;
}

void VideoWriter::copy_into_target() {
  auto fail = [this](int err) {
    abandon();
    throw std::runtime_error("cannot write video '" + out_path_ + "': " + errno_text(err));
  };
  const int in = ::open(tmp_path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) fail(errno);
  int out = -1;
  do {
    out = ::open(target_path_.c_str(), O_WRONLY | O_CLOEXEC);
  } while (out < 0 && errno == EINTR);
  if (out < 0) {
    const int err = errno;
    ::close(in);
    fail(err);
  }
  std::vector<unsigned char> buffer(1 << 16);
  int err = 0;
  for (;;) {
    const ssize_t n = ::read(in, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      err = errno;
      break;
    }
    if (n == 0) break;
    if (!write_all(out, buffer.data(), static_cast<std::size_t>(n))) {
      err = errno;
      break;
    }
  }
  ::close(in);
  if (::close(out) != 0 && !err && errno != EINTR) err = errno;
  if (err) fail(err);
}

void VideoWriter::fail_with_ffmpeg_status(const std::string& what) {
  if (pipe_fd_ >= 0) {
    close(pipe_fd_);
    pipe_fd_ = -1;
  }
  const int status = wait_for_ffmpeg();
  const std::string tail = file_tail(log_path_);
  abandon();
  throw std::runtime_error(what + " while encoding '" + out_path_ + "': ffmpeg " +
                           describe_status(status) +
                           (tail.empty() ? std::string() : "; ffmpeg said: " + tail));
}

int VideoWriter::wait_for_ffmpeg() {
  if (pid_ <= 0) return 0;
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0) {
    if (errno != EINTR) {
      status = 0;
      break;
    }
  }
  pid_ = -1;
  child_guard_.reset();
  return status;
}

void VideoWriter::abandon() noexcept {
  if (pipe_fd_ >= 0) {
    close(pipe_fd_);
    pipe_fd_ = -1;
  }
  if (pid_ > 0) {
    kill(pid_, SIGTERM);
    wait_for_ffmpeg();
  }
  if (!tmp_path_.empty()) std::remove(tmp_path_.c_str());
  if (!log_path_.empty()) std::remove(log_path_.c_str());
  tmp_guard_.reset();
  log_guard_.reset();
  finished_ = true;
}

}  // namespace idmpc::render
