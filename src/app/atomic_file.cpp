#include "app/atomic_file.hpp"

#include "app/output_paths.hpp"
#include "idmpc/experiment/file_paths.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <streambuf>
#include <vector>

namespace idmpc::app {

/// An output stream buffer on a file descriptor that keeps the errno of the first failed write.
class FdStreamBuf : public std::streambuf {
 public:
  explicit FdStreamBuf(int fd) : fd_(fd), buffer_(1 << 16) { reset(); }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!flush_buffer()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return flush_buffer() ? 0 : -1; }

 private:
  void reset() { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  // writes the buffered bytes, retrying short and interrupted writes
  bool flush_buffer() {
    if (error_) return false;
    const char* p = pbase();
    std::size_t left = static_cast<std::size_t>(pptr() - pbase());
    while (left > 0) {
      const ssize_t n = ::write(fd_, p, left);
      if (n < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return false;
      }
      p += n;
      left -= static_cast<std::size_t>(n);
    }
    reset();
    return true;
  }

  int fd_;
  std::vector<char> buffer_;
  int error_ = 0;
};

namespace {

namespace fs = std::filesystem;

std::atomic<unsigned> g_temporary_counter{0};

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (path_.empty()) throw std::runtime_error("cannot write '': empty output path");
  struct stat st {};
  bool existing = false;
  if (::stat(path_.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) fail("it is a directory", 0);
    if (!S_ISREG(st.st_mode)) {
      // a device, FIFO or socket: written through, never replaced
      direct_ = true;
      target_ = path_;
      if (!S_ISFIFO(st.st_mode)) {
        open_direct();
      } else if (::access(path_.c_str(), W_OK) != 0) {
        fail("", errno);
      }
      return;
    }
    existing = true;
  } else if (errno != ENOENT) {
    fail("", errno);  // e.g. a path through a file, a loop of links, no search permission
  }

  target_ = follow_links(path_);
  if (existing && ::access(target_.c_str(), W_OK) != 0) fail("", errno);
  const fs::path parent = fs::path(target_).parent_path();
  const fs::path dir = parent.empty() ? fs::path(".") : parent;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) fail("directory '" + dir.string() + "' does not exist", 0);

  // a fresh temporary beside the target, registered before it exists
  for (;;) {
    tmp_ = temporary_beside(target_, ".", ".tmp." + std::to_string(::getpid()) + "." +
                                               std::to_string(g_temporary_counter++));
    registration_ = std::make_unique<TemporaryFile>(tmp_);
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ >= 0) break;
    const int err = errno;
    registration_.reset();
    if (err != EEXIST) fail("", err);
  }
  if (existing) {
    // the replacement keeps the old file's permissions (and owner, where we may set it)
    if (::geteuid() == 0 && ::fchown(fd_, st.st_uid, st.st_gid) != 0) {
      // best effort: a filesystem without owners keeps ours
    }
    if (::fchmod(fd_, st.st_mode & 07777) != 0) {
      const int err = errno;
      discard();
      fail("cannot keep its permissions", err);
    }
  }
  buf_ = std::make_unique<FdStreamBuf>(fd_);
  out_ = std::make_unique<std::ostream>(buf_.get());
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
  else if (fd_ >= 0) ::close(fd_);
}

void AtomicFile::open_direct() {
  do {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC);
  } while (fd_ < 0 && errno == EINTR);
  if (fd_ < 0) fail("", errno);
  buf_ = std::make_unique<FdStreamBuf>(fd_);
  out_ = std::make_unique<std::ostream>(buf_.get());
}

std::ostream& AtomicFile::stream() {
  if (!out_) open_direct();  // a FIFO, opened at first use
  return *out_;
}

void AtomicFile::commit() {
  if (committed_) return;
  if (!out_) open_direct();
  out_->flush();
  int err = buf_->error();
  if (!err && out_->fail()) err = EIO;
  // the data must be on disk before the rename makes it the target
  if (!err && !direct_ && ::fsync(fd_) != 0 && errno != EINVAL) err = errno;
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 && !err && errno != EINTR) err = errno;
  if (err) {
    discard();
    fail("", err);
  }
  if (!direct_) {
    if (std::rename(tmp_.c_str(), target_.c_str()) != 0) {
      err = errno;
      discard();
      fail("cannot rename the temporary file onto it", err);
    }
    registration_.reset();
  }
  committed_ = true;
}

void AtomicFile::discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!direct_ && !tmp_.empty()) ::unlink(tmp_.c_str());
  registration_.reset();
}

void AtomicFile::fail(const std::string& what, int err) {
  std::string message = "cannot write '" + path_ + "'";
  if (!target_.empty() && target_ != path_) message += " (a link to '" + target_ + "')";
  if (!what.empty()) message += ": " + what;
  if (err) message += std::string(": ") + std::strerror(err);
  throw std::runtime_error(message);
}

AppendFile::AppendFile(std::string path) : path_(std::move(path)) {
  do {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  } while (fd_ < 0 && errno == EINTR);
  if (fd_ < 0) throw std::runtime_error("cannot write '" + path_ + "': " + std::strerror(errno));
}

AppendFile::~AppendFile() {
  if (fd_ >= 0) ::close(fd_);
}

void AppendFile::append(const std::string& text) {
  struct stat st {};
  if (::fstat(fd_, &st) != 0) throw std::runtime_error("cannot write '" + path_ + "': " + std::strerror(errno));
  const char* p = text.data();
  std::size_t left = text.size();
  int err = 0;
  while (left > 0 && !err) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno != EINTR) err = errno;
      continue;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (!err && ::fsync(fd_) != 0 && errno != EINVAL) err = errno;
  if (err) {
    // a regular file is cut back to where this piece began: it keeps every whole piece before it
    if (S_ISREG(st.st_mode) && ::ftruncate(fd_, st.st_size) != 0) {
      // nothing more to do: a torn last line is dropped when the file is read
    }
    throw std::runtime_error("cannot write '" + path_ + "': " + std::strerror(err));
  }
}

}  // namespace idmpc::app
