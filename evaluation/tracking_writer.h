#pragma once
// The JSON and the table of `evaluate tracking` (writer.h): the one place
// its keys and rows are written.

#include <nlohmann/json.hpp>
#include <ostream>

#include "evaluation/tracking_eval.h"

namespace plantscale::app {

nlohmann::json ToJson(const TrackingEvaluation& evaluation);
void WriteTable(const TrackingEvaluation& evaluation, std::ostream& out);

// The JSON of one tracking chain's metrics: evaluate tracking's "ours" keys
// (evaluate log writes the same).
nlohmann::json MetricsJson(const TrackingMetrics& metrics);
// What evaluate tracking --json prints for an empty evaluation with every
// optional part present (the thesis's baseline, an odometry fault): the
// keys `plantscale figures` may quote.
nlohmann::json TrackingJsonShape();

}  // namespace plantscale::app
