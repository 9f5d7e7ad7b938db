#pragma once
// A one-line progress bar on a terminal stream, redrawn at most every 1 %.

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
    last_percent_ = percent;
    const int filled = percent * kWidth / 100;
    out_ << '\r' << label_ << " [" << std::string(static_cast<size_t>(filled), '#')
         << std::string(static_cast<size_t>(kWidth - filled), ' ') << "] " << percent << "% ("
         << done << "/" << total_ << ")" << std::flush;
  }
  void Finish() {
    if (enabled_ && last_percent_ >= 0) out_ << '\n' << std::flush;
  }

 private:
  static constexpr int kWidth = 40;
  std::ostream& out_;
  std::string label_;
  int total_;
  bool enabled_;
  int last_percent_ = -1;
};

}  // namespace plantscale::app
