#include "app/commands.h"

#include "app/segment_commands.h"
#include "app/simulate_commands.h"
#include "app/telemetry_commands.h"

namespace plantscale::app {

CommandLine::CommandLine(CLI::App& cli) : registry_(cli) {
  AddSimulateCommands(registry_);
  AddSegmentCommands(registry_);
  AddTelemetryCommands(registry_);
}

}  // namespace plantscale::app
