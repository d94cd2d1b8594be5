#pragma once
/// @file command.hpp
/// @brief Running a command line in a test: its exit code and captured output.

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace idmpc::test {

struct CommandResult {
  int code = -1;  ///< exit code; -1 when the command did not exit normally (a signal)
  std::string out, err;
};

/// @brief `s` in single quotes for the shell.
std::string quote(const std::string& s);

/// @brief The whole content of a file ("" if it cannot be read).
std::string slurp(const std::filesystem::path& p);

/// @brief The lines of a text, without their line ends.
std::vector<std::string> lines_of(const std::string& text);
/// @brief The fields of a CSV line, a trailing empty field included.
std::vector<std::string> split(const std::string& line, char sep = ',');

/// @brief Runs the shell command `command` in directory `dir`, stdout and stderr captured
/// through the files dir/.stdout and dir/.stderr, removed afterwards.
CommandResult run_command(const std::string& command, const std::filesystem::path& dir);

/// @brief Starts the shell command `command` in the background (`/bin/sh -c`) and returns its
/// process id, for a test that signals or waits for it; -1 if fork failed.
pid_t start_command(const std::string& command);

}  // namespace idmpc::test
