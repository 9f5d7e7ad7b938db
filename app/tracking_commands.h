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
// {"height_m", "tilt_deg", "roll_deg", "focal"}: the sds given, or a seed's draw.
nlohmann::json CalibrationErrorJson(const CalibrationError& error);
// What evaluate tracking --json prints for an empty evaluation with every
// optional part present (the thesis's baseline, an odometry fault): the
// keys `plantscale figures` may quote.
nlohmann::json TrackingJsonShape();

}  // namespace plantscale::app
