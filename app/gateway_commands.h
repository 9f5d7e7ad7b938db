#pragma once
// The remote gateway on the command line (telemetry/gateway/, docs/remote.md):
// `plantscale gateway` serves the vehicle's LCM channels over wss:// to
// Foxglove, Lichtblick and the station; `plantscale users add` issues the
// tokens it accepts.

#include "app/command_registry.h"

namespace plantscale::app {

void AddGatewayCommands(CommandRegistry& registry);

}  // namespace plantscale::app
