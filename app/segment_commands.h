#pragma once
// `plantscale segment` (real photographs or frames) and
// `plantscale evaluate segmentation` (simulator presets against truth).

#include "app/command_registry.h"

namespace plantscale::app {

// `evaluate` is the parent of every `evaluate <what>` command; families add
// their own subcommand to it.
CLI::App* EvaluateCommand(CommandRegistry& registry);

void AddSegmentCommands(CommandRegistry& registry);

}  // namespace plantscale::app
