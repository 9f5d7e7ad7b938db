#pragma once
// `plantscale figures`: every quoted figure from docs/results/figures.yaml
// (evaluation/figures.h, docs/cli/figures.md).

#include "app/command_registry.h"

namespace plantscale::app {

void AddFiguresCommands(CommandRegistry& registry);

}  // namespace plantscale::app
