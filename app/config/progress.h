#pragma once
// A one-line progress bar, redrawn at most every 1 % on a terminal; when
// standard error is not a terminal (logs, CI) a plain line every 10 %.

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <string>

namespace plantscale::app {

class ProgressBar {
 public:
  ProgressBar(std::ostream& out, std::string label, int total, bool enabled)
      : out_(out), label_(std::move(label)), total_(total > 0 ? total : 1), enabled_(enabled) {}

  void Update(int done) {
    if (!enabled_) return;
    const int percent = std::min(100, 100 * done / total_);
    if (percent == last_percent_) return;
    if (!tty_) {
      if (percent / 10 == last_percent_ / 10) return;
      last_percent_ = percent;
      out_ << label_ << ": " << percent << "% (" << done << "/" << total_ << ")\n" << std::flush;
      return;
    }
    last_percent_ = percent;
    const int filled = percent * kWidth / 100;
    out_ << '\r' << label_ << " [" << std::string(static_cast<size_t>(filled), '#')
         << std::string(static_cast<size_t>(kWidth - filled), ' ') << "] " << percent << "% ("
         << done << "/" << total_ << ")" << std::flush;
  }
  void Finish() {
    if (enabled_ && tty_ && last_percent_ >= 0) out_ << '\n' << std::flush;
  }

 private:
  static constexpr int kWidth = 40;
  std::ostream& out_;
  std::string label_;
  int total_;
  bool enabled_;
  int last_percent_ = -1;
  bool tty_ = ::isatty(::fileno(stderr)) != 0;
};

}  // namespace plantscale::app
