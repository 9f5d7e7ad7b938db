#pragma once
// A client's bounded send queue. Under back-pressure (the client's link is
// slower than the vehicle's telemetry) it drops by priority, oldest first:
// camera thumbnails, then trace detail (odometry, pose, nozzles, truth, and
// the grid state beyond 2 Hz); never events, plants, map tiles, health, the
// grid state at 2 Hz or the protocol's own messages. When the messages that
// are never dropped alone outgrow `essential_max_bytes`, Push says so and
// the server closes that client (it reconnects and is sent the map again).

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "engine/common/options.h"
#include "telemetry/gateway/foxglove_convert.h"

namespace plantscale::telemetry::gateway {

enum class DropClass { kThumbnail = 0, kDetail = 1, kEssential = 2 };

struct OutMessage {
  DropClass drop = DropClass::kEssential;
  bool binary = false;
  std::string header;                          // message data header (may be empty)
  std::shared_ptr<const std::string> payload;  // shared between the clients
  size_t bytes() const { return header.size() + (payload ? payload->size() : 0); }
};

struct ClientQueueOptions {
  size_t max_bytes = 512 * 1024;  // droppable messages go beyond this
  size_t essential_max_bytes = 16 * 1024 * 1024;
  int64_t grid_interval_us = 400'000;  // the grid state kept at ≥ 2 Hz (2.5 Hz of 12.5)

  OptionErrors Validate() const;
};

class ClientQueue {
 public:
  explicit ClientQueue(const ClientQueueOptions& options = {});

  // The drop class of a message of `topic_class` stamped `utime` for this
  // client: a grid message is essential when at least grid_interval_us
  // after the last essential one (or with the same stamp: the scene of the
  // same state), else detail.
  DropClass Classify(TopicClass topic_class, int64_t utime);

  // Queues `message`, then drops thumbnails and then detail, oldest first,
  // while the queue holds more than max_bytes. Returns false when what is
  // left exceeds essential_max_bytes (the client cannot keep up).
  bool Push(OutMessage message);
  std::optional<OutMessage> Pop();

  bool empty() const { return queue_.empty(); }
  size_t size() const { return queue_.size(); }
  size_t bytes() const { return bytes_; }
  int64_t dropped(DropClass c) const { return dropped_[static_cast<size_t>(c)]; }

 private:
  bool DropOldest(DropClass c);

  ClientQueueOptions options_;
  std::deque<OutMessage> queue_;
  size_t bytes_ = 0;
  std::array<int64_t, 3> dropped_{};
  int64_t last_grid_utime_ = INT64_MIN;
};

// One event per refused connection or command, rate-limited: a burst of
// `burst` at once, then one per `interval_us`; what was held back is counted
// into the next event ("... and 41 more refusals since 10:02:03").
class RefusalLimiter {
 public:
  explicit RefusalLimiter(int burst = 5, int64_t interval_us = 10'000'000);
  // The event text to publish now for this refusal, or nullopt when held back.
  std::optional<std::string> Refused(int64_t now_us, const std::string& reason);
  // A summary of refusals held back, once the limit allows one; else nullopt.
  std::optional<std::string> Flush(int64_t now_us);
  int64_t held_back() const { return held_back_; }

 private:
  bool Take(int64_t now_us);

  int burst_;
  int64_t interval_us_;
  double tokens_;
  int64_t last_us_ = INT64_MIN;
  int64_t held_back_ = 0;
  std::string last_reason_;
};

}  // namespace plantscale::telemetry::gateway
