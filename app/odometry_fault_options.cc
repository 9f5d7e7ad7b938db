#include "app/odometry_fault_options.h"

#include <stdexcept>

namespace plantscale::app {

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

}  // namespace plantscale::app
