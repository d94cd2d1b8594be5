// idmpc: command-line front end; each sub-command lives in src/app/<name>_command.cpp.
#include <exception>
#include <iostream>

#include "app/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"idmpc: NMPC of robot arms by C/GMRES on forward vs inverse dynamics, "
               "with MuJoCo in the loop"};
  app.require_subcommand(1);
  idmpc::app::register_check(app);
  idmpc::app::register_dynamics(app);
  idmpc::app::register_swingup(app);
  idmpc::app::register_sweep(app);
  idmpc::app::register_render(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "idmpc: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
