#pragma once
// `plantscale evaluate motion`: Sanchiz & Pla correspondence, motion
// recovery and mosaic row fit against simulator truth (issue 7).

#include "app/command_registry.h"

namespace plantscale::app {

void AddMotionCommands(CommandRegistry& registry);

}  // namespace plantscale::app
