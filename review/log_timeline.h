#pragma once
// A log played into a subscriber and run model at a chosen speed, with pause
// and seek (the station's timeline), and a finished run read whole
// (LoadReviewRun: the station's --review of a log). A log file is read as it plays, not held in memory (a 5 km log is
// hundreds of MB); Load reads it through once for its time span. Seeking back
// replays from the start (well under a second for a 100 m run, some seconds
// for kilometres).

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "review/run_model.h"
#include "telemetry/log.h"

namespace plantscale::review {

class LogTimeline {
 public:
  // Events in memory (tests); `error` is the LogReader's complaint (cut-off
  // log), kept for the HUD.
  LogTimeline(std::vector<telemetry::LogEvent> events, std::string error);
  // Streamed from the file. Throws telemetry::LogError when the log cannot be opened.
  static LogTimeline Load(const std::filesystem::path& log);

  // Moves the log clock on by wall_s × speed (nothing while paused).
  void Advance(double wall_s);
  void Seek(double position_s);  // from the first event, clamped to the log
  void SetPaused(bool paused) { paused_ = paused; }
  bool paused() const { return paused_; }
  void SetSpeed(double speed) { speed_ = speed; }
  double speed() const { return speed_; }
  double position_s() const { return position_s_; }
  double duration_s() const;
  int64_t now_utime() const;
  const RunModel& model() const { return *model_; }
  const std::string& error() const { return error_; }
  bool empty() const { return count_ == 0; }

 private:
  LogTimeline() = default;
  void Reset();
  void FeedUpTo(double position_s);
  const telemetry::LogEvent* Peek();  // the next event to feed, nullptr at the end

  std::vector<telemetry::LogEvent> events_;  // in memory, or empty when streamed
  std::filesystem::path file_;               // streamed from here
  std::unique_ptr<telemetry::LogReader> reader_;
  std::optional<telemetry::LogEvent> pending_;  // read from the file, not fed yet
  int64_t first_utime_ = 0, last_utime_ = 0;
  size_t count_ = 0;
  std::string error_;
  std::unique_ptr<telemetry::Subscriber> subscriber_;
  std::unique_ptr<RunModel> model_;
  size_t next_ = 0;
  double position_s_ = 0.0;
  double speed_ = 1.0;
  bool paused_ = false;
};

// A finished run read whole: the run model of a log fed to its end
// (streamed, so only the model stays in memory; the timeline that fed it
// is kept alive by the pointer) and what went wrong reading it.
struct ReviewRun {
  std::shared_ptr<const RunModel> model;
  std::string error;  // the log is cut off or corrupt here (what was read before it is shown)
  bool empty = true;  // not one whole event
};

// Throws telemetry::LogError when the log cannot be opened.
ReviewRun LoadReviewRun(const std::filesystem::path& log);

}  // namespace plantscale::review
