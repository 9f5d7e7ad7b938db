#pragma once
// `plantscale export`: crop maps from a native map file or a simulator
// output folder (several inputs are merged) into GIS files, a PNG and an
// ISOXML task (maps/export.h).

#include "app/command_registry.h"

namespace plantscale::app {

void AddExportCommands(CommandRegistry& registry);

}  // namespace plantscale::app
