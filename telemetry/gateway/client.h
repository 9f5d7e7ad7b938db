#pragma once
// The station's side of the gateway (`station --connect`): a Foxglove
// WebSocket client on Boost.Beast + Asio + OpenSSL that subscribes to the
// gateway's LCM topics (lcm_topics.h) and hands each message's bytes, as
// the vehicle published them, to a callback: the station decodes them with
// the same Subscriber as live LCM, so everything after decoding is the
// same code path.
//
//   - TLS always (wss://), the gateway's certificate checked against --ca
//     (or the system's trusted roots) and its name or IP; plain ws:// only
//     to 127.0.0.1 (a gateway started with --insecure-loopback).
//   - The token goes in an `Authorization: Bearer` header, never in the URL
//     (a URL shows in `ps`, shell histories and proxies' logs).
//   - A lost link is found by WebSocket pings (idle_timeout_s without any
//     data closes it: a cut cable sends no FIN) and reconnected with a
//     backoff capped at reconnect.max_delay_s; the gateway re-sends the
//     latest of each topic and every map tile on subscribing, so the map
//     catches up.
//   - An operator publishes commands (already signed by the station) as
//     plantscale.Command JSON on PLANTSCALE_COMMAND; the gateway rebuilds
//     the LCM message field for field, so the signature still verifies.
//
// Threads: one network thread of its own (from the constructor to the
// destructor); the message callback runs on it. status() and
// PublishCommand() may be called from any thread.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "engine/common/options.h"

class plantscale_command_t;

namespace plantscale::telemetry::gateway {

// A URL, token file or CA file that cannot be used; a gateway that refused
// the token or whose certificate is not trusted (StartAndWait).
class GatewayClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GatewayUrl {
  bool tls = true;
  std::string host;   // a name or an IP address (IPv6 without brackets)
  uint16_t port = 0;  // default 443 (wss) or 80 (ws)
  std::string target = "/";  // path and query sent in the upgrade request
  std::string text;          // the URL as given, for messages
};

// wss://HOST[:PORT][/PATH]; ws:// only with host 127.0.0.1. Throws
// GatewayClientError naming what is wrong (not wss://, no host, a bad port,
// a token in the URL: it belongs in the token file).
GatewayUrl ParseGatewayUrl(const std::string& url);

// The token: the file's first line, white space trimmed (what `plantscale
// users add` printed). Throws GatewayClientError naming the file when it
// cannot be read, is empty, holds white space or control characters inside
// the token, or can be read by group or others (mode 0600, like the users
// file: a token is a password).
std::string ReadTokenFile(const std::filesystem::path& file);

// The delay before reconnect attempt n (n = 1 after the first failure):
// first_delay_s · factor^(n−1), at most max_delay_s. With the defaults,
// 0.25, 0.5, 1, 1, … s: a link that comes back is used again within
// max_delay_s plus one connection attempt. During an outage each attempt's
// SYN goes at 0 and 1 s (the kernel's retransmit) before connect_timeout_s
// gives up, so a returning link waits at most 1 s + max_delay_s for the
// next SYN: with a 2 s cap that was up to 3 s, and with a 1.2 s handshake
// over a 300 ms round trip the reconnect came 4.1–4.7 s after the link
// returned, close to issue 58's 5 s (results/2026-12-07-gateway-link.md).
struct ReconnectPolicy {
  double first_delay_s = 0.25;
  double factor = 2.0;
  double max_delay_s = 1.0;

  double DelayS(int attempt) const;
  OptionErrors Validate() const;
};

struct GatewayClientOptions {
  GatewayUrl url;
  std::string token;
  std::filesystem::path ca_file;  // PEM; empty: the system's trusted roots
  ReconnectPolicy reconnect;
  double connect_timeout_s = 2.0;  // each of TCP connect, TLS and WebSocket handshakes
  double idle_timeout_s = 3.0;     // no data for this long: link lost (ping at half)
  size_t max_message_bytes = 64 * 1024 * 1024;

  OptionErrors Validate() const;
};

enum class LinkState {
  kConnecting,  // the first attempt, or a reconnect under way
  kConnected,   // subscribed
  kWaiting,     // the link failed; the next attempt after a delay
  kRefused,     // the gateway refused the token, or its certificate is not trusted: no retry
};

struct GatewayLinkStatus {
  LinkState state = LinkState::kConnecting;
  std::string url;
  std::string user, role;  // from the gateway's serverInfo, once connected
  bool operator_role = false;
  std::string last_error;   // why the last attempt or link failed
  std::string last_status;  // the gateway's last status message (e.g. a refused command)
  double retry_in_s = 0.0;  // kWaiting: until the next attempt
  int connections = 0;      // successful since start
  int failures = 0;         // consecutive failed attempts
  int64_t messages = 0;     // LCM messages received
  int64_t bytes = 0;
  int64_t commands_sent = 0;
};

// "3.0 s": seconds with one decimal, for the link's messages.
std::string SecondsText(double s);

// "connected to wss://… as alice (operator)", "reconnecting to wss://… in
// 1.0 s: connection refused", …: one line for the station's HUD.
std::string LinkText(const GatewayLinkStatus& status);

class GatewayClient {
 public:
  using OnMessage =
      std::function<void(const std::string& channel, const void* data, size_t size,
                         int64_t recv_utime)>;

  // Reads the CA file and starts the network thread. Throws
  // InvalidOptionsError, GatewayClientError (the CA file).
  GatewayClient(const GatewayClientOptions& options, OnMessage on_message);
  ~GatewayClient();
  GatewayClient(const GatewayClient&) = delete;
  GatewayClient& operator=(const GatewayClient&) = delete;

  // Waits until the first attempt has connected (returns) or has failed
  // for a reason that no retry mends (throws GatewayClientError: the token
  // refused, the certificate not trusted, not a gateway). A network error
  // (refused, unreachable, timeout) is waited out until `timeout_s`, then
  // returns with the client still retrying.
  void WaitFirstAttempt(double timeout_s);

  GatewayLinkStatus status() const;

  // Publishes a command (signed, or not, by the caller) to the vehicle.
  // Returns what happened in words: sent, or why not (not connected, the
  // role is viewer).
  std::string PublishCommand(const plantscale_command_t& command);

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace plantscale::telemetry::gateway
