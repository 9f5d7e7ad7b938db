#pragma once
// Telemetry commands: `run` (the vehicle process on a camera: the whole
// pipeline with --calibration, segmentation alone without), `replay` and
// `telemetry-stats`, and the publishing mode of `simulate` (--publish,
// --fast, --lcm-url, --log, --can), which runs the vehicle runner
// (app/vehicle/runner.h) on the simulator. With --can IFACE the spray bar
// (telemetry/can) is opened on that interface before the camera or the
// simulator; a failure to open it ends the command with the reason.

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "app/command_auth_commands.h"
#include "app/command_registry.h"
#include "app/config/profiles.h"
#include "app/config/run_config.h"
#include "app/gateway_commands.h"
#include "app/vehicle/vehicle_process.h"
#include "engine/sim/simulator.h"
#include "telemetry/can/simulated_bar.h"
#include "telemetry/can/spray_bar.h"

namespace plantscale::app {

struct PublishArgs {
  bool publish = false;
  bool fast = false;
  std::string lcm_url;  // empty: LCM's default udpm:// group
  std::string log;      // empty: no log
  std::string can;      // SocketCAN interface of the spray bar; empty: no bar
  CommandKeyArgs command_key;  // --command-key, --accept-unsigned-commands
  GatewayServeArgs gateway;    // --gateway HOST:PORT --cert --key --users: served from this process
};

void AddPublishOptions(CLI::App* command, PublishArgs& args);
// --can IFACE (in AddPublishOptions and on `run`).
void AddCanOption(CLI::App* command, PublishArgs& args);
// The spray bar of --can: a SocketCAN interface, or (simulate only) the
// word `simulated` for a SimulatedBar in process over a socketpair.
using vehicle::SprayBarEndpoint;  // bar nullptr: no --can
inline constexpr char kSimulatedBar[] = "simulated";
// Throws CanError naming the interface and why it cannot be opened;
// ConfigError for --fast with a real interface, or `simulated` without
// `allow_simulated`.
// A simulated bar has options.num_nozzles nozzles.
SprayBarEndpoint OpenSprayBar(const PublishArgs& args, bool allow_simulated,
                              const telemetry::can::BarLinkOptions& options = {});
using vehicle::VehicleHooks;
// Runs the simulator through the vehicle runner and publishes; prints a
// summary with the traffic per channel. Returns the exit code. `run` (what
// `options` were made from) goes out as the run_config event, for scoring
// the log later (evaluate log).
// The vehicle pipeline is configured from `profiles` only (its camera: the
// vehicle's calibration), never from `options`.
int SimulateAndPublish(const sim::SimulatorOptions& options, const Profiles& profiles,
                       const PublishArgs& args, const SimRunConfig& run,
                       VehicleHooks hooks = {});

void AddTelemetryCommands(CommandRegistry& registry);

}  // namespace plantscale::app
