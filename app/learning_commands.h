#pragma once
// Learned crop/weed segmentation: `train-segmenter` and `evaluate classes`
// (segment --model is in segment_commands.cc).

#include "app/command_registry.h"

namespace plantscale::app {

void AddLearningCommands(CommandRegistry& registry);

}  // namespace plantscale::app
