#pragma once
// `plantscale evaluate log LOG`: a simulated run's vehicle log scored against
// the truth in it (app/log_eval.h), with evaluate treatment's and evaluate
// tracking's metric keys. Exits 1 when the log cannot be read, 2 when it is
// not a simulated run's log (no run_config event, no truth).

#include "app/command_registry.h"

namespace plantscale::app {

void AddLogEvalCommands(CommandRegistry& registry);

}  // namespace plantscale::app
