#pragma once
// `plantscale evaluate treatment`: crop/weed classification, the treatment
// map and the nozzle scheduler against simulator truth (issue 6).

#include <nlohmann/json_fwd.hpp>

#include "app/command_registry.h"
#include "app/treatment_eval.h"

namespace plantscale::app {

void AddTreatmentCommands(CommandRegistry& registry);

// The JSON of one treatment chain's metrics: evaluate treatment's "ours" keys
// (evaluate log writes the same).
nlohmann::json MetricsJson(const TreatmentMetrics& metrics);
// What evaluate treatment --json prints for an empty evaluation with every
// optional part present (the thesis's baseline, an odometry fault, MRROC):
// the keys `plantscale figures` may quote.
nlohmann::json TreatmentJsonShape();

}  // namespace plantscale::app
