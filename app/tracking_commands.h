#pragma once
// `plantscale evaluate tracking`: the grid tracker against simulator truth.

#include <nlohmann/json_fwd.hpp>

#include "app/command_registry.h"
#include "app/tracking_eval.h"

namespace plantscale::app {

void AddTrackingCommands(CommandRegistry& registry);

// The JSON of one tracking chain's metrics: evaluate tracking's "ours" keys
// (evaluate log writes the same).
nlohmann::json MetricsJson(const TrackingMetrics& metrics);
// {"height_m", "tilt_deg", "roll_deg", "focal"}: the amounts (signs per seed).
nlohmann::json CalibrationErrorJson(const CalibrationError& error);

}  // namespace plantscale::app
