#pragma once
// The remote gateway on the command line (telemetry/gateway/, docs/remote.md):
// `plantscale gateway` serves the vehicle's LCM channels over wss:// to
// Foxglove, Lichtblick and the station; `plantscale users add` issues the
// tokens it accepts.

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "app/command_registry.h"
#include "telemetry/gateway/server.h"
#include "telemetry/transport.h"

namespace plantscale::app {

void AddGatewayCommands(CommandRegistry& registry);

// Where and to whom the gateway serves: `gateway`'s --listen, --cert, --key,
// --users, --insecure-loopback, --max-clients; on `run` and `simulate
// --publish`, --gateway HOST:PORT and the same --cert, --key, --users.
struct GatewayServeArgs {
  std::string listen;  // HOST:PORT
  std::string cert, key, users;
  bool insecure_loopback = false;
  int max_clients = telemetry::gateway::GatewayOptions{}.max_clients;
};
// --gateway HOST:PORT --cert --key --users on a vehicle command.
void AddVehicleGatewayOptions(CLI::App* command, GatewayServeArgs& args);

// The gateway inside the vehicle process (one process on a small vehicle
// computer): an LCM instance of its own on the vehicle's URL, served on a
// thread of its own until Stop. Throws ConfigError for a bad listen
// address, certificate, key or users file, and for a memq:// URL (which
// stays inside one LCM instance); TransportError when LCM cannot open.
class BackgroundGateway {
 public:
  BackgroundGateway(const GatewayServeArgs& args, const std::string& lcm_url);
  ~BackgroundGateway();
  BackgroundGateway(const BackgroundGateway&) = delete;
  BackgroundGateway& operator=(const BackgroundGateway&) = delete;
  // "wss://HOST:PORT/" (ws:// with --insecure-loopback).
  std::string address() const;
  // Stops serving (closes every connection) and returns the counts.
  telemetry::gateway::GatewayStats Stop();

 private:
  std::unique_ptr<telemetry::LcmTransport> lcm_;
  std::unique_ptr<telemetry::gateway::Gateway> gateway_;
  std::atomic<bool> stop_{false};
  std::thread loop_;
  std::string scheme_, host_;
  bool stopped_ = false;
};
// One line of the gateway's counts ("N connections, ...").
std::string GatewayStatsText(const telemetry::gateway::GatewayStats& stats);

}  // namespace plantscale::app
