#include "app/commands.h"

#include "app/export_commands.h"
#include "app/simulate_commands.h"

namespace plantscale::app {

CommandLine::CommandLine(CLI::App& cli) : registry_(cli) {
  AddSimulateCommands(registry_);
  AddExportCommands(registry_);
}

}  // namespace plantscale::app
