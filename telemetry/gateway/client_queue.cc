#include "telemetry/gateway/client_queue.h"

#include <algorithm>

namespace plantscale::telemetry::gateway {

OptionErrors ClientQueueOptions::Validate() const {
  OptionErrors e;
  if (max_bytes == 0) e.push_back({"max_bytes", "must be > 0"});
  if (essential_max_bytes < max_bytes) {
    e.push_back(
        {"essential_max_bytes", "must be >= max_bytes (" + std::to_string(max_bytes) + ")"});
  }
  if (grid_interval_us <= 0) e.push_back({"grid_interval_us", "must be > 0"});
  return e;
}

ClientQueue::ClientQueue(const ClientQueueOptions& options) : options_(options) {
  ThrowIfInvalid("ClientQueueOptions", options_.Validate());
}

DropClass ClientQueue::Classify(TopicClass topic_class, int64_t utime) {
  switch (topic_class) {
    case TopicClass::kThumbnail:
      return DropClass::kThumbnail;
    case TopicClass::kDetail:
      return DropClass::kDetail;
    case TopicClass::kEssential:
      return DropClass::kEssential;
    case TopicClass::kGrid:
      break;
  }
  const bool restart = utime < last_grid_utime_;
  if (utime == last_grid_utime_ || restart || last_grid_utime_ == INT64_MIN ||
      utime - last_grid_utime_ >= options_.grid_interval_us) {
    last_grid_utime_ = utime;
    return DropClass::kEssential;
  }
  return DropClass::kDetail;
}

bool ClientQueue::DropOldest(DropClass c) {
  const auto it =
      std::find_if(queue_.begin(), queue_.end(), [c](const OutMessage& m) { return m.drop == c; });
  if (it == queue_.end()) return false;
  bytes_ -= it->bytes();
  ++dropped_[static_cast<size_t>(c)];
  queue_.erase(it);
  return true;
}

bool ClientQueue::Push(OutMessage message) {
  bytes_ += message.bytes();
  queue_.push_back(std::move(message));
  while (bytes_ > options_.max_bytes) {
    if (!DropOldest(DropClass::kThumbnail) && !DropOldest(DropClass::kDetail)) break;
  }
  return bytes_ <= options_.essential_max_bytes;
}

std::optional<OutMessage> ClientQueue::Pop() {
  if (queue_.empty()) return std::nullopt;
  OutMessage m = std::move(queue_.front());
  queue_.pop_front();
  bytes_ -= m.bytes();
  return m;
}

RefusalLimiter::RefusalLimiter(int burst, int64_t interval_us)
    : burst_(std::max(burst, 1)),
      interval_us_(std::max<int64_t>(interval_us, 1)),
      tokens_(burst_) {}

bool RefusalLimiter::Take(int64_t now_us) {
  if (last_us_ != INT64_MIN && now_us > last_us_) {
    tokens_ = std::min<double>(burst_, tokens_ + static_cast<double>(now_us - last_us_) /
                                                     static_cast<double>(interval_us_));
  }
  last_us_ = std::max(last_us_, now_us);
  if (tokens_ < 1.0) return false;
  tokens_ -= 1.0;
  return true;
}

std::optional<std::string> RefusalLimiter::Refused(int64_t now_us, const std::string& reason) {
  if (!Take(now_us)) {
    ++held_back_;
    last_reason_ = reason;
    return std::nullopt;
  }
  std::string text = reason;
  if (held_back_ > 0) {
    text += " (and " + std::to_string(held_back_) + " more refusals held back by the rate limit)";
    held_back_ = 0;
  }
  return text;
}

std::optional<std::string> RefusalLimiter::Flush(int64_t now_us) {
  if (held_back_ == 0 || !Take(now_us)) return std::nullopt;
  std::string text = std::to_string(held_back_) +
                     " refusals held back by the rate limit, the last: " + last_reason_;
  held_back_ = 0;
  return text;
}

}  // namespace plantscale::telemetry::gateway
