#pragma once
// The JSON and the table of `evaluate log` (writer.h): the one place its
// keys and rows are written; the metrics under "treatment" and "tracking"
// are evaluate treatment's and evaluate tracking's (MetricsJson), the keys
// a log cannot give null.

#include <nlohmann/json.hpp>
#include <ostream>

#include "evaluation/log_eval.h"

namespace plantscale::app {

nlohmann::json ToJson(const LogEvaluation& evaluation);
void WriteTable(const LogEvaluation& evaluation, std::ostream& out);

}  // namespace plantscale::app
