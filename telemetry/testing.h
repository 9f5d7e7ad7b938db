#pragma once
// Test helpers: a Transport that records what is published.

#include <string>
#include <vector>

#include "telemetry/codec.h"
#include "telemetry/transport.h"

namespace plantscale::telemetry::testing {

class RecordingTransport : public Transport {
 public:
  struct Sent {
    std::string channel;
    Bytes bytes;
  };
  void Publish(const std::string& channel, const void* data, size_t size) override {
    const auto* b = static_cast<const uint8_t*>(data);
    sent.push_back({channel, Bytes(b, b + size)});
  }
  void Subscribe(const std::string&, Handler) override {}
  bool Handle(int) override { return false; }
  int Count(const std::string& channel) const {
    int n = 0;
    for (const Sent& s : sent) n += s.channel == channel ? 1 : 0;
    return n;
  }
  std::vector<Sent> sent;
};

}  // namespace plantscale::telemetry::testing
