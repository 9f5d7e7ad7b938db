#include "app/odometry_fault.h"

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

void AddOdometryFaultOptions(CLI::App* cmd, OdometryFaultArgs& args) {
  cmd->add_option("--odometry-fault", args.kind,
                  "make the wheel odometry faulty over one stretch: none, spin (both wheels read "
                  "30 % long for 5 m), stall (the left encoder reads 0 for 10 m), stop (no "
                  "odometry for 10 m) or scale (both read 20 % short for 10 m)")
      ->check(CLI::IsMember({"none", "spin", "stall", "stop", "scale"}))
      ->capture_default_str();
  cmd->add_option("--fault-start-m", args.start_m, "where the fault starts (true distance; 15)");
  cmd->add_option("--fault-length-m", args.length_m, "how long it lasts (spin 5, else 10)");
  cmd->add_option("--fault-fraction", args.fraction, "spin's excess, scale's shortfall (0.3, 0.2)");
  cmd->add_flag("--visual-motion", args.visual_motion,
                "the camera's own motion as a second motion source, weighed against the wheels");
}

OdometryFault ToOdometryFault(const OdometryFaultArgs& a) {
  OdometryFault f = DefaultOdometryFault(ParseOdometryFaultKind(a.kind));
  if (a.start_m) f.start_m = *a.start_m;
  if (a.length_m) f.length_m = *a.length_m;
  if (a.fraction) f.fraction = *a.fraction;
  if (!(f.length_m >= 0.0) || !(f.start_m >= 0.0) || !(f.fraction >= 0.0 && f.fraction < 1.0)) {
    throw std::invalid_argument(
        "--fault-start-m and --fault-length-m must be >= 0, --fault-fraction in [0, 1)");
  }
  return f;
}

nlohmann::json OdometryFaultJson(const OdometryFault& f) {
  return {{"kind", Name(f.kind)}, {"start_m", f.start_m}, {"length_m", f.length_m},
          {"fraction", f.fraction}};
}

}  // namespace plantscale::app
