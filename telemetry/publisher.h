#pragma once
// The vehicle's publisher: encodes messages and sends them through a
// Transport within a per-channel rate limit and a total bandwidth budget
// (default 250 kbit/s; 12.5 Hz state channels, 2 Hz thumbnails and
// heartbeat). What is dropped is counted per channel and reason. Rate and
// budget run on message time (utime), so a --fast run drops exactly what a
// real-time run would. A message the transport cannot send (TransportError:
// the network is down, the station's link gone) is counted as failed, never
// thrown: telemetry is not what keeps the vehicle safe (docs/faults.md).

#include <cstdint>
#include <map>
#include <string>

#include "engine/common/options.h"
#include "telemetry/codec.h"
#include "telemetry/transport.h"

namespace plantscale::telemetry {

struct ChannelLimit {
  double max_rate_hz = 12.5;  // 0: no rate limit
  bool essential = false;     // counted in the budget but never dropped by it
};

struct PublisherOptions {
  double budget_kbit_s = 250.0;  // payload bits over all channels
  double burst_s = 0.5;          // the budget may be spent this far ahead
  // A message may take its rate slot this fraction of an interval early, so
  // camera jitter never drops a frame; the average rate stays within the limit.
  double rate_tolerance = 0.25;
  std::map<std::string, ChannelLimit> channels = DefaultChannelLimits();
  ChannelLimit unlisted;  // channels not in the map

  static std::map<std::string, ChannelLimit> DefaultChannelLimits();
  // Keys: "budget_kbit_s", "burst_s", "channels.<NAME>.max_rate_hz", ...
  OptionErrors Validate() const;
};

struct ChannelCounters {
  int64_t sent = 0;
  int64_t bytes = 0;
  int64_t dropped_rate = 0;    // over the channel's rate
  int64_t dropped_budget = 0;  // over the bandwidth budget
  int64_t failed = 0;          // the transport could not send it
};

// The transport's failures, for the heartbeat.
struct TransportFailures {
  int64_t count = 0;          // messages not sent
  int64_t last_utime = -1;    // message time of the latest
  std::string last_error;     // its TransportError::what
};

class Publisher {
 public:
  // Throws InvalidOptionsError. `transport` must outlive the publisher.
  Publisher(Transport& transport, const PublisherOptions& options);

  // Encodes and sends `message` unless the channel's rate or the budget says
  // no; sets the message's seq. Returns true when sent.
  template <typename Message>
  bool Publish(const std::string& channel, Message message) {
    if (!RateAllows(channel, message.utime)) return false;
    message.seq = counters_[channel].sent;
    return PublishBytes(channel, Encode(message), message.utime);
  }
  // The run's last word on `channel` (the end-of-run plant records): sent
  // whatever the rate limit and the budget say, since it comes once.
  template <typename Message>
  void PublishFinal(const std::string& channel, Message message) {
    message.seq = counters_[channel].sent;
    Send(channel, Encode(message), message.utime);
  }
  // True when a message on `channel` at `utime` would pass the rate limit
  // (lets a stage skip costly work, e.g. JPEG encoding, for a dropped frame).
  bool Due(const std::string& channel, int64_t utime) const;
  // Budget check and send for bytes already encoded at message time `utime`.
  bool PublishBytes(const std::string& channel, const Bytes& bytes, int64_t utime);

  const std::map<std::string, ChannelCounters>& counters() const { return counters_; }
  int64_t total_dropped() const;
  const TransportFailures& transport_failures() const { return failures_; }

 private:
  bool RateAllows(const std::string& channel, int64_t utime);
  bool BudgetAllows(const ChannelLimit& limit, size_t bytes, int64_t utime);
  const ChannelLimit& LimitFor(const std::string& channel) const;
  bool Send(const std::string& channel, const Bytes& bytes, int64_t utime);

  Transport& transport_;
  PublisherOptions options_;
  std::map<std::string, ChannelCounters> counters_;
  std::map<std::string, int64_t> next_slot_utime_;
  double budget_bytes_ = 0.0;  // token bucket
  int64_t budget_utime_ = -1;
  TransportFailures failures_;
};

}  // namespace plantscale::telemetry
