#pragma once
// The JSON and the table of `evaluate motion` (writer.h): the one place its
// keys and rows are written.

#include <nlohmann/json.hpp>
#include <ostream>

#include "evaluation/motion_eval.h"

namespace plantscale::app {

// Ours at the top level (the keys the issue names), the paper's method
// under "baseline_paper", the published figures under "published".
nlohmann::json ToJson(const MotionEvaluation& evaluation);
// With paper_in_table, a column for the paper's method beside ours.
void WriteTable(const MotionEvaluation& evaluation, std::ostream& out);

}  // namespace plantscale::app
