#include "review/log_timeline.h"

#include <algorithm>

namespace plantscale::review {

LogTimeline::LogTimeline(std::vector<telemetry::LogEvent> events, std::string error)
    : events_(std::move(events)), count_(events_.size()), error_(std::move(error)) {
  if (!events_.empty()) first_utime_ = events_.front().utime, last_utime_ = events_.back().utime;
  Reset();
}

LogTimeline LogTimeline::Load(const std::filesystem::path& log) {
  LogTimeline t;
  t.file_ = log;
  telemetry::LogReader reader(log);
  while (auto e = reader.Next()) {
    if (t.count_++ == 0) t.first_utime_ = e->utime;
    t.last_utime_ = e->utime;
  }
  t.error_ = reader.error();
  t.Reset();
  return t;
}

void LogTimeline::Reset() {
  telemetry::SubscriberOptions options;
  options.keep_tiles = false;  // the model keeps them (it is fed one tile at a time, RunModel::Feed)
  subscriber_ = std::make_unique<telemetry::Subscriber>(options);
  model_ = std::make_unique<RunModel>();
  model_->Follow(*subscriber_);
  next_ = 0;
  position_s_ = 0.0;
  pending_.reset();
  if (!file_.empty()) reader_ = std::make_unique<telemetry::LogReader>(file_);
}

double LogTimeline::duration_s() const { return count_ == 0 ? 0.0 : 1e-6 * static_cast<double>(last_utime_ - first_utime_); }

int64_t LogTimeline::now_utime() const {
  if (count_ == 0) return 0;
  return first_utime_ + static_cast<int64_t>(position_s_ * 1e6);
}

const telemetry::LogEvent* LogTimeline::Peek() {
  if (!reader_) return next_ < events_.size() ? &events_[next_] : nullptr;
  if (!pending_) pending_ = reader_->Next();
  return pending_ ? &*pending_ : nullptr;
}

void LogTimeline::FeedUpTo(double position_s) {
  position_s_ = std::clamp(position_s, 0.0, duration_s());
  const int64_t until = now_utime();
  for (const telemetry::LogEvent* e = Peek(); e != nullptr && e->utime <= until; e = Peek()) {
    model_->Feed(*subscriber_, e->channel, e->data.data(), e->data.size(), e->utime);  // one look-up per map tile
    if (reader_) pending_.reset();
    else ++next_;
  }
}

void LogTimeline::Advance(double wall_s) {
  if (!paused_) FeedUpTo(position_s_ + wall_s * speed_);
}

void LogTimeline::Seek(double position_s) {
  if (position_s < position_s_) Reset();
  FeedUpTo(position_s);
}

ReviewRun LoadReviewRun(const std::filesystem::path& log) {
  auto timeline = std::make_shared<LogTimeline>(LogTimeline::Load(log));
  timeline->Seek(timeline->duration_s());
  return {std::shared_ptr<const RunModel>(timeline, &timeline->model()), timeline->error(), timeline->empty()};
}

}  // namespace plantscale::review
