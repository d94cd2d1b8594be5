// idmpc swingup MODEL: one closed-loop run of the paper's swing-up, with log, summary and video.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <unistd.h>

#include "app/atomic_file.hpp"
#include "app/commands.hpp"
#include "app/data_dir_option.hpp"
#include "app/output_paths.hpp"
#include "app/swingup.hpp"
#include "app/temporary_files.hpp"
#ifdef IDMPC_HAVE_RENDER
#include "idmpc/render/progress_printer.hpp"
#include "idmpc/render/video.hpp"
#include "idmpc/render/video_writer.hpp"
#endif

namespace idmpc::app {

int& command_exit_code() {
  static int code = 0;
  return code;
}

void register_swingup(CLI::App& app) {
  struct Options {
    TaskOverrides run;
    std::string log, summary, video;
    bool quiet = false;
    double progress = kProgressPeriod;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "swingup", "One closed-loop run of a task (FD or ID, by C/GMRES or the Riccati solver) with MuJoCo in the loop");
  add_task_options(*sub, opt->run);
  add_data_dir_option(*sub);
  sub->add_option("--log", opt->log, "CSV log, one row per control step")->check(non_empty_path());
  sub->add_option("--summary", opt->summary, "JSON summary")->check(non_empty_path());
  sub->add_option("--video", opt->video, "render the run to this MP4 right after it (1280x720, 30 fps)")
      ->check(non_empty_path());
  sub->add_option("--progress", opt->progress,
                  "seconds of wall time between progress lines on standard error (how far the run is and how far "
                  "from its target; 0: every step; at most a day)")
      ->check(CLI::Range(0.0, 86400.0));
  sub->add_flag("--quiet", opt->quiet,
                "no notices (what the run chose by itself) and no progress lines on standard error; warnings and "
                "errors stay");
  sub->callback([opt] {
    const Task task = make_task(opt->run);
    // outputs checked before the run: none is an input or another output, a directory or
    // unwritable, and a video has its encoder
    std::vector<NamedPath> inputs = model_inputs(task.model);
    inputs.push_back({"--task", opt->run.task_file});
    check_output_paths(inputs, {{"--log", opt->log}, {"--summary", opt->summary}, {"--video", opt->video}});
    // the summary records the model, the task file and the log by name
    if (!opt->summary.empty()) {
      check_utf8_paths({{"model", task.model}, {"--task", opt->run.task_file}, {"--log", opt->log}},
                       "--summary records it in JSON");
    }
    if (!opt->log.empty()) AtomicFile probe(opt->log);
    if (!opt->summary.empty()) AtomicFile probe(opt->summary);
#ifndef IDMPC_HAVE_RENDER
    if (!opt->video.empty()) throw std::runtime_error("--video: this build has no renderer (IDMPC_BUILD_RENDER=OFF)");
#else
    if (!opt->video.empty()) {
      render::check_output_writable(opt->video);
      if (render::find_on_path("ffmpeg").empty()) {
        throw std::runtime_error("--video '" + opt->video + "': ffmpeg not found on PATH: install the Debian package ffmpeg");
      }
    }
#endif
    // a video needs a log: without --log, a temporary one in the temporary directory, removed
    // however the command ends
    std::string log = opt->log;
    const bool temporary_log = log.empty() && !opt->video.empty();
    std::optional<TemporaryFile> log_registration;
    struct Cleanup {
      std::string path;
      ~Cleanup() { if (!path.empty()) std::remove(path.c_str()); }
    } cleanup;
    if (temporary_log) {
      log = (std::filesystem::temp_directory_path() / ("idmpc-video-log.tmp." + std::to_string(::getpid()) + ".csv"))
                .string();
      log_registration.emplace(log);
      cleanup.path = log;
    }
    SwingupOutcome out = run_swingup(task, log, opt->run.fallback, RunMessages{!opt->quiet, opt->quiet ? -1.0 : opt->progress});
    if (!opt->summary.empty()) write_json(to_json(out.summary), opt->summary);
    std::cout << human_summary(out.summary);
    if (!opt->log.empty()) std::cout << "  log: " << opt->log << "\n";
    if (!opt->summary.empty()) std::cout << "  summary: " << opt->summary << "\n";
    std::cout << std::flush;
    command_exit_code() = out.summary.diverged ? kDiverged : out.summary.reached ? kReached : kNotReached;
#ifdef IDMPC_HAVE_RENDER
    if (!opt->video.empty()) {
      render::RunLog run = render::read_run_log(log);
      run.formulation = task.formulation;
      run.derivatives = task.derivatives;
      run.label = out.summary.label();
      render::ProgressPrinter progress("rendering " + opt->video);
      render::render_video(task.model, {run}, render::VideoOptions{}, opt->video,
                           [&progress](double frac) { progress(frac); });
      std::cout << "  video: " << opt->video << "\n";
    }
#endif
  });
}

}  // namespace idmpc::app
