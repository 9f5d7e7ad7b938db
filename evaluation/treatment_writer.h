#pragma once
// The JSON and the table of `evaluate treatment` (writer.h): the one place
// its keys and rows are written.

#include <nlohmann/json.hpp>
#include <ostream>

#include "evaluation/treatment_eval.h"

namespace plantscale::app {

nlohmann::json ToJson(const TreatmentEvaluation& evaluation);
void WriteTable(const TreatmentEvaluation& evaluation, std::ostream& out);

// The JSON of one treatment chain's metrics: evaluate treatment's "ours" keys
// (evaluate log writes the same).
nlohmann::json MetricsJson(const TreatmentMetrics& metrics);
// What evaluate treatment --json prints for an empty evaluation with every
// optional part present (the thesis's baseline, an odometry fault, MRROC):
// the keys `plantscale figures` may quote.
nlohmann::json TreatmentJsonShape();

}  // namespace plantscale::app
