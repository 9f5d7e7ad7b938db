#pragma once
// The command-line options of an odometry fault (evaluation/odometry_fault.h)
// shared by `evaluate tracking` and `evaluate treatment`.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "evaluation/odometry_fault.h"

namespace plantscale::app {

// The command-line options: --odometry-fault KIND, --fault-start-m,
// --fault-length-m, --fault-fraction (defaults: DefaultOdometryFault's) and
// --visual-motion (the camera's motion as the second motion source).
struct OdometryFaultArgs {
  std::string kind = "none";
  std::optional<double> start_m, length_m, fraction;
  bool visual_motion = false;
};
void AddOdometryFaultOptions(CLI::App* cmd, OdometryFaultArgs& args);
// Throws std::invalid_argument on a bad kind or a negative length.
OdometryFault ToOdometryFault(const OdometryFaultArgs& args);
}  // namespace plantscale::app
