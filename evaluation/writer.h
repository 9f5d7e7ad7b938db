#pragma once
// The one way an evaluation's result is written. Each evaluation's result
// type (TrackingEvaluation, TreatmentEvaluation, …) has, in its
// *_writer.h beside it, exactly two writers found by argument-dependent
// lookup:
//   nlohmann::json ToJson(const Evaluation&);             // `--json`
//   void WriteTable(const Evaluation&, std::ostream&);     // the text table
// and the commands print either with WriteEvaluation. The JSON keys and the
// tables are a contract (docs/cli/, `plantscale figures` quotes the JSON):
// they are written here and nowhere else. Below: the parts that more than
// one evaluation writes.

#include <nlohmann/json.hpp>
#include <ostream>

#include "app/config/profiles.h"
#include "evaluation/engine_used.h"

namespace plantscale::app {

// One JSON object (pretty-printed, two spaces, then a newline) or the table.
template <class Evaluation>
void WriteEvaluation(const Evaluation& evaluation, bool json, std::ostream& out) {
  if (json) {
    out << ToJson(evaluation).dump(2) << '\n';
  } else {
    WriteTable(evaluation, out);
  }
}

// The value, or null when it is not finite (JSON has no NaN).
nlohmann::json Finite(double value);
// {"height_m", "tilt_deg", "roll_deg", "focal"}: the sds given, or a seed's draw.
nlohmann::json CalibrationErrorJson(const CalibrationError& error);
// "crop", "vehicle" and "calibration_error" (the sds) into `j`.
void AddEngineJson(const EngineUsed& engine, nlohmann::json& j);
// "  engine: crop C, vehicle V, calibration error TEXT|none".
void WriteEngineLine(const EngineUsed& engine, std::ostream& out);

}  // namespace plantscale::app
