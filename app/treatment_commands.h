#pragma once
// `plantscale evaluate treatment`: crop/weed classification, the treatment
// map and the nozzle scheduler against simulator truth (issue 6).

#include "app/command_registry.h"

namespace plantscale::app {

void AddTreatmentCommands(CommandRegistry& registry);

}  // namespace plantscale::app
