#pragma once
/// @file video_writer.hpp
/// @brief H.264 MP4 encoding by piping raw RGB frames into an ffmpeg child process.

#include <functional>
#include <memory>
#include <string>
#include <sys/types.h>

namespace idmpc::render {

/// @brief Told of each temporary file the renderer makes (the video beside its output, ffmpeg's
/// log, a probe of a directory) before the file is created; returns a guard that is dropped once
/// the file is gone or renamed. The command line registers them for removal when a signal ends
/// the process. Unset (the default), nothing is told.
using TemporaryRegistrar = std::function<std::shared_ptr<void>(const std::string& path)>;
/// @brief Told of the ffmpeg process writing a temporary video once it is started; its guard is
/// dropped once the process has been waited for (the command line kills it on a signal).
using ChildRegistrar = std::function<std::shared_ptr<void>(pid_t pid)>;
void set_temporary_registrar(TemporaryRegistrar files, ChildRegistrar children);

/// @brief Full path of an executable named `name` on PATH, or "" when there is none.
std::string find_on_path(const std::string& name);

/// @brief Checks that a file can be created at `path` (its directory exists, is a directory and
/// is writable, and `path` itself is not a directory) without creating it, or that `path` is a
/// writable special file (a device or FIFO, which is written through); a symbolic link is
/// followed. Throws std::runtime_error naming the path and the reason otherwise.
void check_output_writable(const std::string& path);

/// @brief Writes an MP4 (H.264, yuv420p) from raw RGB frames through `ffmpeg`.
///
/// ffmpeg writes to a hidden temporary file next to the output (`.<name>.tmp.<pid>.<k>.mp4`;
/// for a special file, in the temporary directory), which finish() renames onto the
/// output once ffmpeg exits cleanly (a symbolic link is followed and stays a link; a replaced
/// file keeps its permissions; a special file such as a character device or FIFO is never
/// replaced: the finished video is copied into it); abandoning the writer (destruction without finish(), for
/// example during an exception) stops ffmpeg and removes the temporary file, so a failed run
/// never leaves a truncated video behind. ffmpeg's stderr goes to a temporary log whose tail
/// is quoted when ffmpeg fails.
class VideoWriter {
 public:
  /// @brief Starts ffmpeg. width and height must be positive and even (yuv420p), fps > 0.
  /// Throws std::invalid_argument for bad sizes and std::runtime_error when ffmpeg is not on
  /// PATH or cannot be started, or the temporary files cannot be created.
  VideoWriter(const std::string& out_mp4, int width, int height, double fps);
  ~VideoWriter();

  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  VideoWriter(VideoWriter&&) = delete;
  VideoWriter& operator=(VideoWriter&&) = delete;

  /// @brief Appends one frame: width*height*3 bytes of RGB, rows from top to bottom.
  /// Throws std::runtime_error (with ffmpeg's exit status and stderr tail) if ffmpeg died.
  void write_frame(const unsigned char* rgb);

  /// @brief Closes the stream, waits for ffmpeg and moves the video to its output path.
  /// Throws std::runtime_error with the exit status and ffmpeg's stderr tail on failure.
  void finish();

  int width() const { return width_; }
  int height() const { return height_; }
  int frames() const { return frames_; }

 private:
  [[noreturn]] void fail_with_ffmpeg_status(const std::string& what);
  int wait_for_ffmpeg();
  void abandon() noexcept;
  void copy_into_target();

  std::string out_path_;     // as given
  std::string target_path_;  // links followed: the file replaced or written through
  bool direct_ = false;      // target is a special file: written through, never replaced
  int existing_mode_ = -1;   // permission bits of the file replaced, or -1
  uid_t existing_uid_ = 0;
  gid_t existing_gid_ = 0;
  std::string tmp_path_;
  std::string log_path_;
  std::shared_ptr<void> tmp_guard_, log_guard_, child_guard_;  // registrations (set_temporary_registrar)
  int width_ = 0;
  int height_ = 0;
  int frames_ = 0;
  int pipe_fd_ = -1;
  pid_t pid_ = -1;
  bool finished_ = false;
};

}  // namespace idmpc::render
