// A text progress bar on stderr for the command-line tools, drawn only when stderr is a terminal.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <string>

namespace novaphy {

class ProgressBar {
 public:
  ProgressBar(int total, std::string what, bool enabled = true)
      : total_(total), what_(std::move(what)), enabled_(enabled && isatty(STDERR_FILENO)) {}

  // marks `done` of total finished; redraws when the bar grows
  void update(int done) {
    const int width = 40, filled = total_ > 0 ? width * done / total_ : width;
    if (!enabled_ || (filled == filled_ && done != total_)) return;
    filled_ = filled;
    std::fprintf(stderr, "\r%s [%s%s] %d/%d", what_.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), done, total_);
    if (done == total_) std::fprintf(stderr, "\n");
  }

 private:
  int total_;
  std::string what_;
  bool enabled_;
  int filled_ = -1;
};

}  // namespace novaphy
