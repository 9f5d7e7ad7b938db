#include "telemetry/transport.h"

#include <chrono>
#include <lcm/lcm-cpp.hpp>

#include "engine/common/options.h"

namespace plantscale::telemetry {

int64_t WallUtime() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

OptionErrors LcmTransportOptions::Validate() const {
  OptionErrors errors;
  if (url.find("://") == std::string::npos) {
    errors.push_back(
        {"url", "must look like provider://address, e.g. udpm:// or memq:// (got '" + url + "')"});
  }
  return errors;
}

namespace {

constexpr int kQueueCapacity = 10000;

// The station drains its socket between renders while a vehicle under --fast
// (or the end-of-run flush of some 16 map tiles) publishes in bursts. The
// drops seen were LCM's queue (below), not the socket; still, the kernel's
// default 208 KiB receive buffer holds only a few such tiles, so udpm:// URLs
// without an explicit recv_buf_size ask for 2 MiB (the kernel caps it at
// net.core.rmem_max without failing).
std::string WithReceiveBuffer(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=2097152";
}

}  // namespace

LcmTransport::LcmTransport(const std::string& url)
    : url_(url), lcm_(std::make_unique<lcm::LCM>(WithReceiveBuffer(url))) {
  if (!lcm_->good()) {
    throw TransportError("LCM URL '" + url +
                         "': cannot start (for udpm:// add a multicast route, e.g. "
                         "'ip route add 224.0.0.0/4 dev lo')");
  }
}

LcmTransport::~LcmTransport() = default;

void LcmTransport::Publish(const std::string& channel, const void* data, size_t size) {
  if (lcm_->publish(channel, data, static_cast<unsigned int>(size)) != 0) {
    throw TransportError("LCM URL '" + url_ + "': publish on " + channel + " failed (" +
                         std::to_string(size) + " bytes)");
  }
}

void LcmTransport::Subscribe(const std::string& channel_regex, Handler handler) {
  handlers_.push_back(std::make_unique<Handler>(std::move(handler)));
  Handler* h = handlers_.back().get();
  lcm::Subscription* subscription = lcm_->subscribeFunction(
      channel_regex,
      +[](const lcm::ReceiveBuffer* rbuf, const std::string& channel, Handler* target) {
        (*target)(ReceivedMessage{channel, rbuf->data, rbuf->data_size, rbuf->recv_utime});
      },
      h);
  // LCM keeps only 30 undispatched messages per subscription and silently
  // drops the rest: the station, rendering between Handle calls, lost the
  // end-of-run tile flush and the run_finished event behind it in 1 of 4
  // demos. A run's whole burst fits in this many.
  subscription->setQueueCapacity(kQueueCapacity);
}

bool LcmTransport::Handle(int timeout_ms) {
  const int status = lcm_->handleTimeout(timeout_ms);
  if (status < 0) throw TransportError("LCM URL '" + url_ + "': handle failed");
  return status > 0;
}

}  // namespace plantscale::telemetry
