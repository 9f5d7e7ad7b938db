#include "ui/station_timeline.h"

#include <algorithm>

namespace plantscale::ui {

LogTimeline::LogTimeline(std::vector<telemetry::LogEvent> events, std::string error)
    : events_(std::move(events)), error_(std::move(error)) {
  Reset();
}

LogTimeline LogTimeline::Load(const std::filesystem::path& log) {
  telemetry::LogReader reader(log);
  std::vector<telemetry::LogEvent> events;
  while (auto e = reader.Next()) events.push_back(std::move(*e));
  return LogTimeline(std::move(events), reader.error());
}

void LogTimeline::Reset() {
  subscriber_ = std::make_unique<telemetry::Subscriber>();
  model_ = std::make_unique<RunModel>();
  model_->Follow(*subscriber_);
  next_ = 0;
  position_s_ = 0.0;
}

double LogTimeline::duration_s() const {
  if (events_.empty()) return 0.0;
  return 1e-6 * static_cast<double>(events_.back().utime - events_.front().utime);
}

int64_t LogTimeline::now_utime() const {
  if (events_.empty()) return 0;
  return events_.front().utime + static_cast<int64_t>(position_s_ * 1e6);
}

void LogTimeline::FeedUpTo(double position_s) {
  position_s_ = std::clamp(position_s, 0.0, duration_s());
  const int64_t until = now_utime();
  while (next_ < events_.size() && events_[next_].utime <= until) {
    const telemetry::LogEvent& e = events_[next_++];
    model_->Feed(*subscriber_, e.channel, e.data.data(), e.data.size(), e.utime);  // one look-up per map tile
  }
}

void LogTimeline::Advance(double wall_s) {
  if (!paused_) FeedUpTo(position_s_ + wall_s * speed_);
}

void LogTimeline::Seek(double position_s) {
  if (position_s < position_s_) Reset();
  FeedUpTo(position_s);
}

}  // namespace plantscale::ui
