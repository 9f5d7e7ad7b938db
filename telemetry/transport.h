#pragma once
// The transport behind every publisher and subscriber (the Drake habit):
// publish bytes on a channel, subscribe to channels by regular expression,
// dispatch what has arrived with a timeout. LcmTransport is real LCM with
// any URL (`udpm://` default; unit tests use `memq://`).

#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/common/options.h"

namespace lcm {
class LCM;
}

namespace plantscale::telemetry {

// Transport set-up or I/O failure (bad URL, no multicast route, write error).
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ReceivedMessage {
  const std::string& channel;
  const void* data;
  size_t size;
  int64_t recv_utime;  // wall clock at reception, microseconds
};

class Transport {
 public:
  using Handler = std::function<void(const ReceivedMessage&)>;
  virtual ~Transport() = default;

  // Throws TransportError when the bytes could not be sent.
  virtual void Publish(const std::string& channel, const void* data, size_t size) = 0;
  // `channel_regex` is matched against whole channel names (LCM semantics).
  virtual void Subscribe(const std::string& channel_regex, Handler handler) = 0;
  // Dispatches pending messages to handlers, waiting up to `timeout_ms` for
  // the first; returns false on timeout. Throws TransportError on failure.
  virtual bool Handle(int timeout_ms) = 0;
};

struct LcmTransportOptions {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";  // LCM's default group, host only

  // Keys: "url".
  OptionErrors Validate() const;
};

class LcmTransport : public Transport {
 public:
  // Throws TransportError naming the URL when LCM cannot start (for udpm://
  // most often a missing multicast route: ip route add 224.0.0.0/4 dev lo).
  explicit LcmTransport(const std::string& url);
  ~LcmTransport() override;

  void Publish(const std::string& channel, const void* data, size_t size) override;
  void Subscribe(const std::string& channel_regex, Handler handler) override;
  bool Handle(int timeout_ms) override;
  const std::string& url() const { return url_; }

 private:
  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Handler>> handlers_;
};

// Microseconds since the Unix epoch (LCM's utime convention).
int64_t WallUtime();

}  // namespace plantscale::telemetry
