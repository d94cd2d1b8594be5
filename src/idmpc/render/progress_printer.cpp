#include "idmpc/render/progress_printer.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace idmpc::render {
namespace {

constexpr int kPlainStep = 10;  // percent between plain lines

}  // namespace

ProgressPrinter::ProgressPrinter(std::string label, std::FILE* stream)
    : ProgressPrinter(std::move(label), stream, isatty(fileno(stream)) != 0) {}

ProgressPrinter::ProgressPrinter(std::string label, std::FILE* stream, bool terminal)
    : label_(std::move(label)), stream_(stream), terminal_(terminal) {}

ProgressPrinter::~ProgressPrinter() {
  // an interrupted job leaves the terminal on a fresh line for what follows
  if (line_open_) {
    std::fputc('\n', stream_);
    std::fflush(stream_);
  }
}

void ProgressPrinter::operator()(double fraction) {
  // whole percent done, clamped (a NaN counts as nothing done)
  const double clamped = std::isnan(fraction) ? 0.0 : std::clamp(fraction, 0.0, 1.0);
  const int percent = static_cast<int>(clamped * 100 + 1e-9);
  if (percent <= shown_) return;

  // terminal: redraw the line in place, end it at 100 %
  if (terminal_) {
    shown_ = percent;
    std::fprintf(stream_, "\r%s: %3d%%", label_.c_str(), percent);
    line_open_ = percent < 100;
    if (!line_open_) std::fputc('\n', stream_);
    std::fflush(stream_);
    return;
  }
  // elsewhere: one plain line per completed tenth
  const int tenth = percent / kPlainStep * kPlainStep;
  if (tenth <= std::max(shown_, 0)) return;
  shown_ = tenth;
  std::fprintf(stream_, "%s: %d%%\n", label_.c_str(), tenth);
  std::fflush(stream_);
}

}  // namespace idmpc::render
