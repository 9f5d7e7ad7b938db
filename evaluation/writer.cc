#include "evaluation/writer.h"

#include <cmath>

namespace plantscale::app {

nlohmann::json Finite(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json CalibrationErrorJson(const CalibrationError& c) {
  return {{"height_m", c.height_m}, {"tilt_deg", c.tilt_deg}, {"roll_deg", c.roll_deg},
          {"focal", c.focal}};
}

void AddEngineJson(const EngineUsed& engine, nlohmann::json& j) {
  j["crop"] = engine.crop;
  j["vehicle"] = engine.vehicle;
  j["calibration_error"] = CalibrationErrorJson(engine.calibration_error);
  if (!engine.segmenter_model.empty()) j["segmenter_model"] = engine.segmenter_model;
}

void WriteEngineLine(const EngineUsed& engine, std::ostream& out) {
  out << "  engine: crop " << engine.crop << ", vehicle " << engine.vehicle
      << ", calibration error "
      << (engine.calibration_error_text.empty() ? "none" : engine.calibration_error_text)
      << (engine.segmenter_model.empty() ? "" : ", segmenter model " + engine.segmenter_model) << '\n';
}

}  // namespace plantscale::app
