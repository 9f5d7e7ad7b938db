#pragma once
// `plantscale simulate`, `demo` and `presets`.

#include "app/command_registry.h"

namespace plantscale::app {

void AddSimulateCommands(CommandRegistry& registry);

}  // namespace plantscale::app
