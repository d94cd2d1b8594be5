// idmpc: command-line front end; each sub-command lives in src/app/<name>_command.cpp.
// Every error, a command-line one included, is one line "idmpc: error: …" and exit code 1;
// --help and --version print to stdout and exit 0. Standard output is flushed at the end: a
// command whose output could not be written (a full disk, /dev/full) fails.
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <sys/stat.h>

#include "app/commands.hpp"
#include "app/temporary_files.hpp"

#ifndef IDMPC_VERSION
#error "IDMPC_VERSION comes from src/CMakeLists.txt: the project's version"
#endif

namespace {

// CLI11 takes "-.4" for a short option "-."; spell such a number "-0.4" (the same double).
// "-0.4", "-1e-3" and "-5" already parse as numbers. Arguments after "--" are left alone.
std::vector<std::string> normalized_arguments(int argc, char** argv) {
  std::vector<std::string> args(argv, argv + argc);
  for (std::size_t k = 1; k < args.size(); ++k) {
    std::string& a = args[k];
    if (a == "--") break;
    if (a.size() < 3 || a[0] != '-' || a[1] != '.' || !std::isdigit(static_cast<unsigned char>(a[2]))) {
      continue;
    }
    char* end = nullptr;
    std::strtod(a.c_str(), &end);
    if (end && *end == '\0') a.insert(1, "0");
  }
  return args;
}

std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  for (std::size_t pos = text.find('\n'); pos != std::string::npos; pos = text.find('\n', pos)) {
    text.replace(pos, 1, "; ");
  }
  return text;
}

// CLI11 lists unexpected arguments in no useful order ("10 --horizon"): put them in the
// order they were given
std::string unexpected_arguments(const std::string& what, const std::vector<std::string>& args) {
  const std::size_t colon = what.find(": ");
  if (colon == std::string::npos) return what;
  std::istringstream in(what.substr(colon + 2));
  std::vector<std::string> extras;
  for (std::string token; in >> token;) extras.push_back(token);
  std::string ordered;
  std::vector<bool> used(args.size(), false);
  std::size_t found = 0;
  for (std::size_t k = 1; k < args.size(); ++k) {
    for (const std::string& e : extras) {
      if (!used[k] && args[k] == e) {
        ordered += (found++ ? " " : "") + args[k];
        used[k] = true;
      }
    }
  }
  if (found != extras.size()) return what;
  const bool option = !ordered.empty() && ordered[0] == '-';
  return std::string(option ? "unknown option or unexpected argument" : "unexpected argument") +
         (extras.size() > 1 ? "s" : "") + " '" + ordered + "'";
}

// the command: its exit code
int run(int argc, char** argv) {
  CLI::App app{"idmpc: NMPC of robot arms by C/GMRES on forward vs inverse dynamics, "
               "with MuJoCo in the loop"};
  app.set_version_flag("--version", std::string("idmpc " IDMPC_VERSION " (MuJoCo ") +
                                        mj_versionString() + ")");
  app.require_subcommand(1);
  idmpc::app::register_check(app);
  idmpc::app::register_dynamics(app);
  idmpc::app::register_swingup(app);
  idmpc::app::register_sweep(app);
  idmpc::app::register_render(app);

  const std::vector<std::string> args = normalized_arguments(argc, argv);
  std::vector<char*> c_args;
  for (const std::string& a : args) c_args.push_back(const_cast<char*>(a.c_str()));
  try {
    app.parse(static_cast<int>(c_args.size()), c_args.data());
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with exit code 0
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::string message = one_line(e.what());
    if (dynamic_cast<const CLI::ExtrasError*>(&e)) message = unexpected_arguments(message, args);
    const std::vector<CLI::App*> subs = app.get_subcommands();
    if (subs.empty() && args.size() > 1 && args[1][0] != '-') {
      // the first word is no command
      std::string names;
      const auto all = app.get_subcommands([](const CLI::App*) { return true; });
      for (std::size_t k = 0; k < all.size(); ++k) {
        names += (k == 0 ? "" : k + 1 == all.size() ? " or " : ", ") + all[k]->get_name();
      }
      message = "unknown command '" + args[1] + "': expected " + names;
    }
    const std::string help = subs.empty() ? "idmpc --help" : "idmpc " + subs.back()->get_name() + " --help";
    std::cerr << "idmpc: error: " << message << " (see '" << help << "')\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "idmpc: error: " << one_line(e.what()) << "\n";
    return 1;
  }
  return idmpc::app::command_exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  // line by line into a pipe (`idmpc sweep | tee log`): the log shows each line when it is said,
  // not at the end (a terminal is line-buffered already; files and devices keep the full buffer,
  // whose one flush at the end reports a failed write with its reason)
  struct stat out {};
  if (fstat(fileno(stdout), &out) == 0 && S_ISFIFO(out.st_mode)) std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);
  idmpc::app::install_temporary_file_cleanup();
  const int code = run(argc, argv);
  // what the command printed must have reached its destination
  // (std::cout writes through stdout's buffer: its flush would be the first to fail, and a
  // second fflush has no error number to tell)
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int err = errno;
  std::cout.flush();
  if (!flushed || std::ferror(stdout) || std::cout.fail()) {
    if (code == 1) return code;  // its error is said already
    std::cerr << "idmpc: error: cannot write to standard output"
              << (err ? std::string(": ") + std::strerror(err) : std::string()) << "\n";
    return 1;
  }
  return code;
}
