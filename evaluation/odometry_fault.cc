#include "evaluation/odometry_fault.h"

#include <stdexcept>

namespace plantscale::app {

OdometryFaultKind ParseOdometryFaultKind(const std::string& word) {
  for (OdometryFaultKind k : {OdometryFaultKind::kNone, OdometryFaultKind::kSpin,
                              OdometryFaultKind::kStall, OdometryFaultKind::kStop,
                              OdometryFaultKind::kScale}) {
    if (word == Name(k)) return k;
  }
  throw std::invalid_argument("--odometry-fault: '" + word +
                              "' is not one of none, spin, stall, stop, scale");
}

const char* Name(OdometryFaultKind kind) {
  switch (kind) {
    case OdometryFaultKind::kNone: return "none";
    case OdometryFaultKind::kSpin: return "spin";
    case OdometryFaultKind::kStall: return "stall";
    case OdometryFaultKind::kStop: return "stop";
    case OdometryFaultKind::kScale: return "scale";
  }
  return "?";
}

OdometryFault DefaultOdometryFault(OdometryFaultKind kind) {
  OdometryFault f;
  f.kind = kind;
  f.length_m = kind == OdometryFaultKind::kSpin ? 5.0 : 10.0;
  f.fraction = kind == OdometryFaultKind::kScale ? 0.2 : 0.3;
  return f;
}

bool ApplyOdometryFault(const OdometryFault& fault, double distance_m, sim::OdometrySample& s) {
  if (!fault.Active(distance_m)) return true;
  switch (fault.kind) {
    case OdometryFaultKind::kNone: break;
    case OdometryFaultKind::kSpin:
      s.left_m_s = (1.0 + fault.fraction) * s.true_left_m_s;
      s.right_m_s = (1.0 + fault.fraction) * s.true_right_m_s;
      break;
    case OdometryFaultKind::kStall: s.left_m_s = 0.0; break;
    case OdometryFaultKind::kStop: return false;
    case OdometryFaultKind::kScale:
      s.left_m_s *= 1.0 - fault.fraction;
      s.right_m_s *= 1.0 - fault.fraction;
      break;
  }
  return true;
}

nlohmann::json OdometryFaultJson(const OdometryFault& f) {
  return {{"kind", Name(f.kind)}, {"start_m", f.start_m}, {"length_m", f.length_m},
          {"fraction", f.fraction}};
}

}  // namespace plantscale::app
