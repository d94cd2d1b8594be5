#pragma once
/// @file video.hpp
/// @brief Off-screen replay of closed-loop run logs in MuJoCo, encoded to an MP4 video.

#include <functional>
#include <string>
#include <vector>

#include "idmpc/render/run_log.hpp"

namespace idmpc::render {

/// @brief How a video is rendered.
struct VideoOptions {
  int width = 1280;   ///< pixels, positive and even
  int height = 720;   ///< pixels, positive and even
  double fps = 30;    ///< video frames per second
  double speed = 1.0; ///< log seconds per video second (0.5 = slow motion)
  /// "auto" (a free camera framing the whole motion, looking across the plane of motion of a
  /// planar arm), "fixed:<name>" (a camera of the model), or "azimuth,elevation,distance"
  /// (degrees, degrees, metres; a free camera aimed at the centre of the motion).
  std::string camera = "auto";
  /// text table (time, run labels, |u|, residual, update time) and |u| plot over the scene
  bool overlay = true;
  /// multisample anti-aliasing with the model's off-screen samples (vis.quality.offsamples,
  /// MuJoCo's default 4): smoother edges for about twice the software rendering time; off, the
  /// scene is rendered with one sample per pixel
  bool antialias = false;
  /// longest video accepted, in seconds of video (1 h): a log that would need more than
  /// fps x this many frames is refused before anything is loaded or rendered
  double max_video_seconds = 3600;
};

/// @brief Checks the options; throws std::invalid_argument naming the bad option, the expected
/// range and the value it got.
void check_video_options(const VideoOptions& options);

/// @brief Number of frames of a video of `log_seconds` of log: one every speed/fps log seconds,
/// both ends shown. Throws std::invalid_argument naming the count and the bound when the video
/// would be longer than options.max_video_seconds (e.g. a 2-row log spanning 33000 s at 30 fps:
/// 990001 frames, over the 108000 of one hour).
long video_frame_count(double log_seconds, const VideoOptions& options);

/// @brief Renders the runs replayed in the model to an H.264 MP4 at `out_mp4`.
///
/// One run: the arm in the model's own colours, with an overlay of the time, the run's label,
/// the torque norm |u|, the optimality residual and the update time, and a plot of |u| over
/// time. Two runs (compare mode): both arms in one scene, the FD run (or else the first) solid
/// blue and the other as a thinner solid orange core drawn just in front of it, so identical
/// motion shows one blue arm with an orange stripe and any difference shows two arms; the
/// overlay becomes a colour legend with both runs' values and the plot shows both |u| curves.
/// A run whose log has a frame target (columns x..z_ref) also shows the target's path over the
/// whole run as magenta dots, the frame's travelled path up to the current time as a green trail
/// (its run's colour in compare mode) and the current target as a larger magenta sphere; the
/// overlay adds the frame's position error in mm and a legend of the paths.
/// The free camera frames the whole motion and the paths beside the overlays. Frames sample the logs at `fps`
/// and real time x `speed` (each frame shows the log row nearest its time); a run that ends
/// early (or diverges to non-finite values) holds its last finite pose.
///
/// @param model_path MJCF file whose nq equals every log's joint count
/// @param runs one or two logs from read_run_log
/// @param progress called after each frame with the fraction of frames done, in (0, 1]
/// Throws std::invalid_argument for bad options, logs that do not fit the model or a video
/// longer than options.max_video_seconds (before any loading or rendering), and
/// std::runtime_error for an unwritable output, a missing ffmpeg, or a GL/encoding failure;
/// a failed render leaves no partial file at `out_mp4`.
void render_video(const std::string& model_path, const std::vector<RunLog>& runs,
                  const VideoOptions& options, const std::string& out_mp4,
                  const std::function<void(double)>& progress = {});

}  // namespace idmpc::render
