#pragma once
// `--odometry-fault KIND` of `evaluate tracking` and `evaluate treatment`:
// the simulator's wheel odometry made faulty over one stretch of the run,
// to measure how the grid rides through it (with the visual motion source,
// engine/pipeline/visual_motion.h, or without it).
//
//   spin  both drive wheels read `fraction` long (30 %: spinning on wet soil)
//   stall the left wheel's encoder reads 0 (a stalled or unplugged encoder)
//   stop  no odometry sample arrives at all
//   scale both wheels read `fraction` short (a wrong tyre radius)
//
// The stretch starts `start_m` into the run (true distance) and lasts
// `length_m`; the defaults per kind are DefaultOdometryFault's.

#include <nlohmann/json.hpp>
#include <string>

#include "engine/sim/vehicle.h"

namespace plantscale::app {

enum class OdometryFaultKind { kNone, kSpin, kStall, kStop, kScale };

struct OdometryFault {
  OdometryFaultKind kind = OdometryFaultKind::kNone;
  double start_m = 15.0;
  double length_m = 10.0;
  double fraction = 0.3;

  bool Active(double distance_m) const {
    return kind != OdometryFaultKind::kNone && distance_m >= start_m &&
           distance_m < start_m + length_m;
  }
};

// "none", "spin", "stall", "stop", "scale"; throws std::invalid_argument
// naming the word otherwise.
OdometryFaultKind ParseOdometryFaultKind(const std::string& word);
const char* Name(OdometryFaultKind kind);
// spin: 30 % for 5 m; stall, stop: 10 m; scale: 20 % short for 10 m; all
// from 15 m into the run.
OdometryFault DefaultOdometryFault(OdometryFaultKind kind);

// The sample as the faulty odometry reports it, `distance_m` (true) into
// the run. False: the sample never arrives (stop).
bool ApplyOdometryFault(const OdometryFault& fault, double distance_m, sim::OdometrySample& sample);

nlohmann::json OdometryFaultJson(const OdometryFault& fault);

}  // namespace plantscale::app
