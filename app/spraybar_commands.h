#pragma once
// `plantscale spraybar`: a diagnostic of the spray bar (telemetry/can) on a
// SocketCAN interface or the simulated bar: supervises it in real time for a
// few seconds (all nozzles closed, or a walking test pattern) and reports
// heartbeats, acknowledgements, rejected frames, fail-safe reasons and
// per-nozzle faults.

#include "app/command_registry.h"

namespace plantscale::app {

void AddSprayBarCommands(CommandRegistry& registry);

}  // namespace plantscale::app
