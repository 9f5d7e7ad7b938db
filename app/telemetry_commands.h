#pragma once
// Telemetry commands: `replay` and `telemetry-stats`, and the publishing
// mode of `simulate` (--publish, --fast, --lcm-url, --log), which runs the
// vehicle runner (telemetry/runner.h) on the simulator.

#include <CLI/CLI.hpp>
#include <string>

#include "app/command_registry.h"
#include "engine/sim/simulator.h"

namespace plantscale::app {

struct PublishArgs {
  bool publish = false;
  bool fast = false;
  std::string lcm_url;  // empty: LCM's default udpm:// group
  std::string log;      // empty: no log
};

void AddPublishOptions(CLI::App* command, PublishArgs& args);
// Runs the simulator through the vehicle runner and publishes; prints a
// summary with the traffic per channel. Returns the exit code.
int SimulateAndPublish(const sim::SimulatorOptions& options, const PublishArgs& args);

void AddTelemetryCommands(CommandRegistry& registry);

}  // namespace plantscale::app
