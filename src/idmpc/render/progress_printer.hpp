#pragma once
/// @file progress_printer.hpp
/// @brief Progress of a long job ("rendering x.mp4: 42%") printed to a stream, redrawn in place
/// on a terminal and as occasional plain lines otherwise.

#include <cstdio>
#include <string>

namespace idmpc::render {

/// @brief Prints "<label>: <percent>%" for fractions of a job done.
///
/// On a terminal the line is redrawn in place ('\r') at every whole percent and ended with a
/// newline at 100 % (or when the printer is destroyed before, e.g. on an error). Anywhere else
/// (a file, a pipe, a CI log) it prints a plain line at every 10 %, so logs hold ten lines and
/// no carriage returns. Pass it to render_video through a lambda that calls it by reference.
class ProgressPrinter {
 public:
  /// @brief Tells a terminal with isatty(fileno(stream)).
  explicit ProgressPrinter(std::string label, std::FILE* stream = stderr);
  /// @brief As above with the terminal decision given (tests).
  ProgressPrinter(std::string label, std::FILE* stream, bool terminal);
  ~ProgressPrinter();

  ProgressPrinter(const ProgressPrinter&) = delete;
  ProgressPrinter& operator=(const ProgressPrinter&) = delete;

  /// @brief Reports `fraction` of the job done, in [0, 1]; prints only when the shown
  /// percentage (terminal) or tenth (otherwise) advanced.
  void operator()(double fraction);

  bool terminal() const { return terminal_; }

 private:
  std::string label_;
  std::FILE* stream_;
  bool terminal_;
  int shown_ = -1;            // last percentage printed
  bool line_open_ = false;    // a terminal line without its newline yet
};

}  // namespace idmpc::render
