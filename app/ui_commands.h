#pragma once
// `plantscale station` (the operator's window, live over LCM or replaying a
// log) and `plantscale report` (off-screen pictures and index.html from a log).

#include "app/command_registry.h"

namespace plantscale::app {

void AddUiCommands(CommandRegistry& registry);

}  // namespace plantscale::app
