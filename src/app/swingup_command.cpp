// idmpc swingup MODEL: one closed-loop run of the paper's swing-up, with log and summary.
#include <iostream>

#include "app/commands.hpp"
#include "app/atomic_file.hpp"
#include "app/swingup.hpp"

namespace idmpc::app {

void register_swingup(CLI::App& app) {
  struct Options {
    SwingupOptions run;
    std::string log, summary;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand("swingup", "Closed-loop swing-up by C/GMRES (FD or ID) with MuJoCo in the loop");
  sub->add_option("model", opt->run.model, "MJCF/URDF model file")->required();
  add_swingup_options(*sub, opt->run);
  sub->add_option("--log", opt->log, "CSV log, one row per control step");
  sub->add_option("--summary", opt->summary, "JSON summary");
  sub->callback([opt] {
    if (!opt->summary.empty()) {
      AtomicFile probe(opt->summary);  // fail on an unwritable path before the run
    }
    SwingupOutcome out = run_swingup(opt->run, opt->log);
    if (!opt->summary.empty()) write_json(out.summary, opt->summary);
    std::cout << human_summary(out.summary);
    if (!opt->log.empty()) std::cout << "  log: " << opt->log << "\n";
    if (!opt->summary.empty()) std::cout << "  summary: " << opt->summary << "\n";
  });
}

}  // namespace idmpc::app
