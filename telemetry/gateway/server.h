#pragma once
// The gateway's server: the vehicle's LCM channels served over wss:// (TLS
// always; plain ws:// only with insecure_loopback on 127.0.0.1) with the
// Foxglove WebSocket protocol, on Boost.Beast + Asio + OpenSSL.
//
//   - Every connection is authenticated at the HTTP upgrade, before any
//     channel is advertised: a token (`?token=` or `Authorization: Bearer`)
//     whose salted hash is in the users file (users.h); a missing or wrong
//     one is answered 401 and closed, and becomes one event on
//     PLANTSCALE_GATEWAY_EVENTS, rate-limited (RefusalLimiter).
//   - A viewer sees; an operator may also advertise PLANTSCALE_COMMAND and
//     publish commands (JSON, plantscale.Command), forwarded to LCM field
//     for field: the station's HMAC signature goes through unchanged and
//     the vehicle checks it (the gateway holds no key and cannot forge one).
//   - Each client has a bounded queue that drops by priority (client_queue.h).
//   - A client that asks (lcm=1 in the query: the station) is also served
//     each LCM channel's bytes as they came (lcm_topics.h).
//   - A client that subscribes is sent the latest message of the topic at
//     once, for map tiles every tile's newest revision and for plants every
//     plant's newest observation (paced by its link), so a reconnecting
//     client gets the whole map and every plant again.
//   - Stop sends each client what is queued (up to stop_drain_s), then
//     closes the WebSockets.
//
// Threads: one network thread (Start/Stop) owns every connection; the
// transport's handler (whoever calls Transport::Handle, see RunTransportLoop)
// converts LCM messages to JSON and hands them over. Outgoing LCM messages
// (commands, the gateway's events) are published by FlushOutgoing on the
// transport's thread.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "engine/common/options.h"
#include "telemetry/gateway/client_protocol.h"
#include "telemetry/gateway/client_queue.h"
#include "telemetry/gateway/users.h"
#include "telemetry/transport.h"

namespace plantscale::telemetry::gateway {

// TLS files that cannot be used, an address that cannot be bound.
class GatewayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GatewayOptions {
  std::string host = "127.0.0.1";   // an IP address to listen on (0.0.0.0: every interface)
  int port = 8765;                  // 0: any free port (port() tells which)
  std::filesystem::path cert_file;  // PEM certificate chain; required unless insecure_loopback
  std::filesystem::path key_file;   // PEM private key of that certificate
  bool insecure_loopback = false;   // plain ws://, only with host 127.0.0.1
  int max_clients = 32;
  int max_pending = 64;
  // Map tiles kept to send a new client (a 5 km bed's tiles as JSON are
  // ~150 MB); tiles beyond it are served live but not to later clients.
  size_t max_cached_tile_bytes =
      256 * 1024 * 1024;         // connections in TLS handshake or upgrade; more are closed at once
  int handshake_timeout_s = 10;  // TLS handshake and HTTP upgrade
  std::string name = "plantscale gateway";
  ClientQueueOptions queue;
  ProtocolLimits limits;
  // PLANTSCALE_GRID/scene at most this often in message time (0: every
  // grid message): a 3-D view needs no more than 2.5 Hz, and at 12.5 Hz the
  // scene was a third of every client's bytes (results/2026-12-07-gateway.md).
  int64_t grid_scene_interval_us = 400'000;
  // At Stop, each client's queued messages (the run's last map tiles, a
  // reconnected client's catch-up) are sent for at most this long, then
  // every connection closes: the end of a run reaches a client on a slow link.
  double stop_drain_s = 5.0;
  // Bytes written to a client's socket but not yet sent that the kernel may
  // hold (TCP_NOTSENT_LOWAT): 16 kB is 0.13 s at 1 Mbit/s. What is beyond
  // waits in the client's queue, dropped by priority (client_queue.h).
  size_t max_unsent_bytes = 16 * 1024;
  int refusal_burst = 5;  // refusal events at once, then one per interval
  int64_t refusal_interval_us = 10'000'000;

  // Keys: the field names.
  OptionErrors Validate() const;
};

struct GatewayStats {
  int clients = 0;
  int64_t connections = 0;   // accepted WebSocket sessions
  int64_t refused = 0;       // connections refused (token, upgrade, too many)
  int64_t shed = 0;          // closed at accept: max_pending handshakes already
  int64_t lcm_messages = 0;  // received from the transport
  int64_t lcm_rejected = 0;  // could not be decoded or converted
  int64_t commands_forwarded = 0;
  int64_t commands_refused = 0;  // viewer, unadvertised channel, bad JSON
  int64_t protocol_errors = 0;   // malformed or unsupported client messages
  int64_t dropped_thumbnails = 0;
  int64_t dropped_detail = 0;
  int64_t slow_clients_closed = 0;
  int64_t tiles_not_cached = 0;  // beyond max_cached_tile_bytes
  int64_t refusal_events = 0;    // events published for refusals (rate-limited)
};

class Gateway {
 public:
  // Loads the certificate and key, binds the address and subscribes to every
  // channel of `transport` (which must outlive the gateway). Throws
  // InvalidOptionsError, GatewayError naming the file or address.
  Gateway(const GatewayOptions& options, Users users, Transport& transport);
  ~Gateway();
  Gateway(const Gateway&) = delete;
  Gateway& operator=(const Gateway&) = delete;

  void Start();  // the network thread
  void Stop();   // drains (stop_drain_s), closes every connection and joins the thread
  uint16_t port() const;
  // Empty, or why every client will refuse the certificate (it expired, or
  // is not valid yet): the gateway starts anyway, the caller says so.
  const std::string& certificate_warning() const;
  GatewayStats stats() const;
  // Publishes the commands and events waiting to go out on the transport.
  // Call from the thread that calls transport.Handle.
  void FlushOutgoing();

  struct Impl;  // server.cc: the network state its sessions share

 private:
  std::unique_ptr<Impl> impl_;
};

// The transport's handler refers to the gateway: do not handle the
// transport after the gateway is destroyed.
//
// Handles the transport and flushes the gateway's outgoing messages until
// `stop` is set. Throws TransportError.
void RunTransportLoop(Transport& transport, Gateway& gateway, const std::atomic<bool>& stop);

}  // namespace plantscale::telemetry::gateway
