// idmpc render MODEL --log RUN.csv --out RUN.mp4: replays closed-loop logs off-screen to MP4.
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "app/number_options.hpp"
#include "app/output_paths.hpp"

#ifdef IDMPC_HAVE_RENDER
#include "idmpc/render/progress_printer.hpp"
#include "idmpc/render/run_log.hpp"
#include "idmpc/render/video.hpp"
#include "idmpc/render/video_writer.hpp"
#endif

namespace idmpc::app {
namespace {

struct RenderArgs {
  std::string model;
  std::string log;
  std::vector<std::string> compare;
  std::string out;
  int width = 1280;
  int height = 720;
  double fps = 30;
  double speed = 1.0;
  std::string camera = "auto";
  bool no_overlay = false;
  bool antialias = false;
};

#ifdef IDMPC_HAVE_RENDER

void run_render(const RenderArgs& args) {
  // exactly one source of runs
  if (args.log.empty() == args.compare.empty()) {
    throw std::invalid_argument(
        "render: expected exactly one of --log RUN.csv or --compare A.csv B.csv, got " +
        std::string(args.log.empty() ? "neither" : "both"));
  }
  if (!args.compare.empty() && args.compare.size() != 2) {
    throw std::invalid_argument("--compare: expected two run logs, got " +
                                std::to_string(args.compare.size()));
  }
  render::VideoOptions options;
  options.width = args.width;
  options.height = args.height;
  options.fps = args.fps;
  options.speed = args.speed;
  options.camera = args.camera;
  options.overlay = !args.no_overlay;
  options.antialias = args.antialias;
  render::check_video_options(options);
  // inputs: the model with the files it includes, each log and the summary beside it (read for
  // the run's label and model)
  std::vector<NamedPath> inputs = model_inputs(args.model);
  auto add_log = [&inputs](const std::string& option, const std::string& path) {
    inputs.push_back({option, path});
    if (path.empty()) return;
    const std::string summary = std::filesystem::path(path).replace_extension(".json").string();
    std::error_code ec;
    if (std::filesystem::exists(summary, ec)) inputs.push_back({option + "'s summary", summary});
  };
  add_log("--log", args.log);
  for (const std::string& path : args.compare) add_log("--compare", path);
  check_output_paths(inputs, {{"--out", args.out}});
  render::check_output_writable(args.out);

  std::vector<render::RunLog> runs;
  if (!args.log.empty()) {
    runs.push_back(render::read_run_log(args.log));
  } else {
    for (const auto& path : args.compare) runs.push_back(render::read_run_log(path));
  }
  for (const render::RunLog& run : runs) {
    if (!run.summary_warning.empty()) std::cerr << "idmpc: warning: " << run.summary_warning << "\n";
  }

  // "rendering x.mp4: 42%" on stderr: in place on a terminal, every 10% otherwise
  render::ProgressPrinter printer("rendering " + args.out);
  render::render_video(args.model, runs, options, args.out,
                       [&printer](double f) { printer(f); });
  std::cout << "wrote " << args.out << " (" << options.width << "x" << options.height << ", "
            << options.fps << " fps, speed " << options.speed << "x)\n";
}

#else

void run_render(const RenderArgs&) {
  throw std::runtime_error("render: this idmpc was built without rendering; expected a build "
                           "with -DIDMPC_BUILD_RENDER=ON (needs libosmesa6-dev), got it OFF");
}

#endif

}  // namespace

void register_render(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand(
      "render", "Replay closed-loop run logs in MuJoCo off-screen and encode an MP4 (H.264)");
  sub->add_option("model", args->model, "MJCF model file the runs were made with")->required();
  CLI::Option* log = sub->add_option("--log", args->log, "run log CSV written by idmpc swingup");
  CLI::Option* compare =
      sub->add_option("--compare", args->compare,
                      "two run logs in one scene: the FD run blue, the other an orange core")
          ->expected(2);
  log->excludes(compare);
  sub->add_option("--out,-o", args->out, "output video (.mp4)")->required()->check(non_empty_path());
  sub->add_option("--width", args->width, "video width in pixels (even)")->capture_default_str();
  sub->add_option("--height", args->height, "video height in pixels (even)")
      ->capture_default_str();
  sub->add_option("--fps", args->fps, "video frames per second")->capture_default_str();
  sub->add_option("--speed", args->speed, "playback speed (log seconds per video second)")
      ->capture_default_str();
  sub->add_option("--camera", args->camera,
                  "auto | fixed:<model camera> | azimuth,elevation,distance (deg, deg, m)")
      ->capture_default_str();
  sub->add_flag("--no-overlay", args->no_overlay, "no text table and |u| plot over the scene");
  sub->add_flag("--antialias", args->antialias,
                "multisample anti-aliasing (the model's offsamples): smoother edges, about twice the rendering time");
  require_decimal_numbers(*sub);
  sub->callback([args] { run_render(*args); });
}

}  // namespace idmpc::app
