#pragma once
// The JSON and the tables of `evaluate rows` (writer.h), on the simulator
// and on labelled photographs (`--images`): the one place their keys and
// lines are written.

#include <nlohmann/json.hpp>
#include <ostream>

#include "evaluation/rows_eval.h"

namespace plantscale::app {

nlohmann::json ToJson(const RowsEvaluation& evaluation);
void WriteTable(const RowsEvaluation& evaluation, std::ostream& out);

// CRDA on labelled photographs.
nlohmann::json ToJson(const PhotoRowsEvaluation& evaluation);
void WriteTable(const PhotoRowsEvaluation& evaluation, std::ostream& out);
// The JSON of an empty photograph evaluation with a model: the keys
// `plantscale figures` may quote.
nlohmann::json PhotoRowsJsonShape();

}  // namespace plantscale::app
