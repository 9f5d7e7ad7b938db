#pragma once
// `plantscale evaluate tracking`: the grid tracker against simulator truth.

#include "app/command_registry.h"

namespace plantscale::app {

void AddTrackingCommands(CommandRegistry& registry);

}  // namespace plantscale::app
