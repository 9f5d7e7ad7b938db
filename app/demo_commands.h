#pragma once
// `plantscale demo` (what ./plantscale.sh demo runs) and `demo-system`, the
// same command: the whole system on the simulator, each part its own
// process (app/processes.h): the vehicle (`simulate --publish`) over LCM
// and logging, the station subscribing (a window with DISPLAY, else
// off-screen under one xvfb-run for the whole demo), then the report of the
// log, the maps (`export`) and the run in a season archive (`export --to`).
// Outputs under --out (default out/demo): run.lcmlog, station.png,
// report/, maps/, archive.gpkg and each process's output (*.txt).

#include "app/command_registry.h"

namespace plantscale::app {

void AddDemoCommands(CommandRegistry& registry);

}  // namespace plantscale::app
