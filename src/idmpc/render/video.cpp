#include "idmpc/render/video.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/render/camera.hpp"
#include "idmpc/render/close_up.hpp"
#include "idmpc/render/frame_path.hpp"
#include "idmpc/render/gl_context.hpp"
#include "idmpc/render/replay.hpp"
#include "idmpc/render/run_overlay.hpp"
#include "idmpc/render/scene_dressing.hpp"
#include "idmpc/render/video_writer.hpp"

namespace idmpc::render {
namespace {

constexpr int kMaxSize = 8192;  // pixels per side
constexpr double kMaxFps = 240;
constexpr double kMaxSpeed = 1000;
constexpr double kMaxVideoSeconds = 24 * 3600;  // bound of the bound: a day of video

std::string fmt(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

// MuJoCo's abstract scene, freed with it
struct Scene {
  mjvScene scn;
  Scene(const mjModel* m, int maxgeom) {
    mjv_defaultScene(&scn);
    mjv_makeScene(m, &scn, maxgeom);
  }
  ~Scene() { mjv_freeScene(&scn); }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
};

// MuJoCo's GL resources on the current context, with its off-screen framebuffer
struct RenderContext {
  mjrContext con;
  RenderContext(const mjModel* m, int fontscale) {
    mjr_defaultContext(&con);
    try {
      mjr_makeContext(m, &con, fontscale);
    } catch (const std::exception& e) {
      mjr_freeContext(&con);
      throw std::runtime_error(
          std::string("MuJoCo could not set up OpenGL on the OSMesa context (mjr_makeContext): ") +
          e.what());
    }
    if (!con.offFBO) {
      mjr_freeContext(&con);
      throw std::runtime_error("MuJoCo's off-screen framebuffer: expected a framebuffer object, "
                               "got none (OpenGL without framebuffer objects?)");
    }
  }
  ~RenderContext() { mjr_freeContext(&con); }
  RenderContext(const RenderContext&) = delete;
  RenderContext& operator=(const RenderContext&) = delete;
};

}  // namespace

void check_video_options(const VideoOptions& options) {
  for (const auto& [name, v] : {std::pair<const char*, int>{"--width", options.width},
                                std::pair<const char*, int>{"--height", options.height}}) {
    if (v < 2 || v > kMaxSize || v % 2 != 0) {
      throw std::invalid_argument(std::string(name) + ": expected an even number of pixels in 2.." +
                                  std::to_string(kMaxSize) + " (H.264 yuv420p), got " +
                                  std::to_string(v));
    }
  }
  if (!(options.fps > 0) || options.fps > kMaxFps) {
    throw std::invalid_argument("--fps: expected 0 < fps <= " + fmt("%g", kMaxFps) + ", got " +
                                fmt("%g", options.fps));
  }
  if (!(options.speed > 0) || options.speed > kMaxSpeed) {
    throw std::invalid_argument("--speed: expected 0 < speed <= " + fmt("%g", kMaxSpeed) +
                                ", got " + fmt("%g", options.speed));
  }
  if (!(options.max_video_seconds > 0) || options.max_video_seconds > kMaxVideoSeconds) {
    throw std::invalid_argument("max_video_seconds: expected 0 < seconds <= " +
                                fmt("%g", kMaxVideoSeconds) + ", got " +
                                fmt("%g", options.max_video_seconds));
  }
  parse_camera(options.camera);
}

long video_frame_count(double log_seconds, const VideoOptions& options) {
  // both ends shown: t0, t0 + step, ..., the last frame at or just before the end
  const double step = options.speed / options.fps;
  const double count = std::floor(std::max(log_seconds, 0.0) / step + 1e-9) + 1;
  // at most max_video_seconds of video at the given fps
  const double limit = std::ceil(options.max_video_seconds * options.fps);
  if (!(count <= limit)) {
    throw std::invalid_argument(
        "video length: expected at most " + fmt("%.0f", limit) + " frames (" +
        fmt("%g", options.max_video_seconds) + " s of video at --fps " + fmt("%g", options.fps) +
        "), got " + fmt("%.0f", count) + " frames (" + fmt("%g", log_seconds) +
        " s of log at --speed " + fmt("%g", options.speed) +
        "); raise --speed or render a shorter log");
  }
  return static_cast<long>(count);
}

void render_video(const std::string& model_path, const std::vector<RunLog>& runs,
                  const VideoOptions& options, const std::string& out_mp4,
                  const std::function<void(double)>& progress) {
  // everything cheap is checked before any GL or ffmpeg work
  check_video_options(options);
  if (runs.empty() || runs.size() > 2) {
    throw std::invalid_argument("runs: expected one log (or two to compare), got " +
                                std::to_string(runs.size()));
  }
  // compare mode: the FD run (or else the first) is the blue arm, the other the orange core
  const bool compare = runs.size() == 2;
  std::vector<std::size_t> order{0};
  if (compare) order = (runs[0].formulation == "id" && runs[1].formulation != "id")
                           ? std::vector<std::size_t>{1, 0}
                           : std::vector<std::size_t>{0, 1};
  std::vector<Replay> replays;
  std::vector<Rgb> colours;
  for (std::size_t i : order) {
    replays.emplace_back(runs[i]);
    colours.push_back(compare ? (replays.size() == 1 ? kBlue : kOrange) : kSinglePlot);
  }
  // the frames' times; a video too long is refused here
  const Schedule schedule = make_schedule(replays, options);

  // the model; the logs, the camera name and the output checked against it
  mj::ModelPtr model = mj::load_model(model_path);
  mjModel* m = model.get();
  for (const RunLog& run : runs) check_run_log(run, m, model_path);
  const CameraSpec camera_spec = parse_camera(options.camera);
  const int fixed_camid = find_fixed_camera(m, camera_spec, model_path);
  check_output_writable(out_mp4);
  if (find_on_path("ffmpeg").empty()) {
    throw std::runtime_error("ffmpeg not found on PATH: install the Debian package ffmpeg");
  }

  // one mjData per run; where the motion goes over the whole video
  std::vector<mj::DataPtr> data_owner;
  std::vector<mjData*> datas;
  for (std::size_t r = 0; r < replays.size(); ++r) {
    data_owner.push_back(mj::make_data(m));
    datas.push_back(data_owner.back().get());
  }
  mjvOption opt;
  mjv_defaultOption(&opt);
  const Motion motion = measure_motion(m, datas, replays, schedule, opt);

  // the runs' frame paths (none for logs without frame columns), a few pixels thick
  std::vector<FramePath> paths;
  int path_geoms = 0;
  for (const Replay& r : replays) {
    paths.emplace_back(*r.log, trail_radius(motion.visible));
    path_geoms += paths.back().max_geoms();
  }
  // the first run with a frame path shows the target's path and the current target
  const auto target_path = static_cast<std::size_t>(
      std::find_if(paths.begin(), paths.end(), [](const FramePath& p) { return !p.empty(); }) - paths.begin());

  // GL: OSMesa context and MuJoCo's off-screen buffer at the video size
  GlContext gl(options.width, options.height);
  m->vis.global.offwidth = options.width;
  m->vis.global.offheight = options.height;
  if (!options.antialias) m->vis.quality.offsamples = 0;
  RenderContext context(m, font_scale_for(options.height));
  mjrContext& con = context.con;
  mjr_setBuffer(mjFB_OFFSCREEN, &con);
  if (con.currentBuffer != mjFB_OFFSCREEN) {
    throw std::runtime_error("MuJoCo could not select its off-screen framebuffer");
  }
  const mjrRect viewport{0, 0, options.width, options.height};

  // the abstract scene: every run's geoms, the paths and the dressing
  Scene scene(m, static_cast<int>(replays.size()) * m->ngeom + path_geoms + 1200);
  mjvScene& scn = scene.scn;

  // overlays, the camera framing the motion beside them, then the overlays moved off the
  // robot wherever this camera shows it
  RunOverlay overlay(replays, colours, schedule, options, con);
  FreeCamera free_cam;
  mjvCamera cam = make_camera(m, camera_spec, fixed_camid, motion, free_regions(overlay.regions()),
                              static_cast<double>(options.width) / options.height, free_cam);
  Vec3 view_forward, view_up, view_right;
  camera_axes(free_cam.azimuth, free_cam.elevation, view_forward, view_up, view_right);
  ScreenMask footprint(1, 1);
  if (options.overlay) {
    footprint = robot_footprint(m, datas, replays, schedule, opt, cam, scn, options.width, options.height, paths);
    overlay.avoid(footprint);
  }
  // a close-up of a small target path (a free camera's angles; none with the model's cameras)
  const CloseUp close_up =
      options.overlay && target_path < paths.size() && camera_spec.kind != CameraSpec::Kind::kFixed
          ? plan_close_up(paths[target_path], motion.visible, free_cam.azimuth, free_cam.elevation,
                          m->vis.global.fovy, options.width, options.height, overlay.places(), footprint,
                          std::max(4, options.height / 80))
          : CloseUp{};

  // scene dressing where the model has none
  const bool dress_floor = !has_plane(m);
  const bool dress_light = m->nlight == 0;
  const bool dress_sky = !has_skybox(m);

  // the encoder and the read-back buffers
  VideoWriter writer(out_mp4, options.width, options.height, options.fps);
  const std::size_t row_bytes = static_cast<std::size_t>(options.width) * 3;
  std::vector<unsigned char> pixels(row_bytes * static_cast<std::size_t>(options.height));
  std::vector<unsigned char> frame(pixels.size());

  // the scene seen by a camera: the first run (all categories), then the second run's moving
  // geoms, the paths and the dressing
  const auto build_scene = [&](mjvCamera& view, double t) {
    mjv_updateScene(m, datas[0], &opt, nullptr, &view, mjCAT_ALL, &scn);
    if (compare) {
      const Vec3 eye{0.5 * (scn.camera[0].pos[0] + scn.camera[1].pos[0]),
                     0.5 * (scn.camera[0].pos[1] + scn.camera[1].pos[1]),
                     0.5 * (scn.camera[0].pos[2] + scn.camera[1].pos[2])};
      recolour(scn, m, 0, colours[0]);
      const int first = scn.ngeom;
      mjv_addGeoms(m, datas[1], &opt, nullptr, mjCAT_DYNAMIC, &scn);
      keep_moving_geoms(scn, m, first);
      recolour(scn, m, first, colours[1]);
      make_cores(scn, m, first, eye);
    }
    // the frame paths: the target's, then each run's trail (in its colour when comparing)
    for (std::size_t r = 0; r < replays.size(); ++r) {
      paths[r].add(scn, replays[r].pose_row(t), r == target_path, compare ? colours[r] : kToolPath);
    }
    if (dress_floor) add_floor(scn, motion.visible);
    if (dress_light) add_key_light(scn, motion.visible, view_forward);
  };
  mjvCamera close_up_cam = close_up.cam;

  for (long k = 0; k < schedule.frames; ++k) {
    const double t = schedule.time(k);
    for (std::size_t r = 0; r < replays.size(); ++r) set_pose(m, datas[r], replays[r], t);
    build_scene(cam, t);
    mjr_render(viewport, &scn, &con);
    if (close_up.shown) {
      // without shadows and reflections: their passes cost as much in a corner as in the frame
      build_scene(close_up_cam, t);
      const mjtByte shadow = scn.flags[mjRND_SHADOW], reflection = scn.flags[mjRND_REFLECTION];
      scn.flags[mjRND_SHADOW] = scn.flags[mjRND_REFLECTION] = 0;
      mjr_render(close_up.rect, &scn, &con);
      scn.flags[mjRND_SHADOW] = shadow;
      scn.flags[mjRND_REFLECTION] = reflection;
    }
    if (dress_sky) draw_sky(options.width, options.height);
    draw_close_up_border(close_up);

    // overlays
    overlay.draw(t);

    // read back (GL rows run bottom-up) and encode
    mjr_readPixels(pixels.data(), nullptr, viewport, &con);
    for (int y = 0; y < options.height; ++y) {
      std::memcpy(frame.data() + static_cast<std::size_t>(y) * row_bytes,
                  pixels.data() + static_cast<std::size_t>(options.height - 1 - y) * row_bytes,
                  row_bytes);
    }
    writer.write_frame(frame.data());
    if (progress) progress(static_cast<double>(k + 1) / static_cast<double>(schedule.frames));
  }
  writer.finish();
}

}  // namespace idmpc::render
