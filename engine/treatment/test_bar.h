#pragma once
// The spray bar and safety inputs shared by the scheduler's tests
// (treatment_test.cc, bar_uncertainty_test.cc).

#include <cstdint>

#include "engine/treatment/nozzle_scheduler.h"

namespace plantscale::treatment::testing {

// Eight nozzles 5 cm apart, 0.5 m behind the camera, with the given valve
// latency; the fail-safe's limits are the scheduler's defaults.
inline SchedulerOptions TestBar(double valve_latency_s) {
  SchedulerOptions o;
  o.bar.nozzles = 8;
  o.bar.nozzle_spacing_m = 0.05;
  o.bar.bar_offset_m = 0.5;
  o.bar.valve_latency_s = valve_latency_s;
  return o;
}

// Every input the bar's safety checks read, fresh at `now` and tracking.
inline SafetyInputs Healthy(int64_t now) {
  SafetyInputs s;
  s.pose_utime = now;
  s.last_frame_utime = now;
  s.tracking = true;
  return s;
}

}  // namespace plantscale::treatment::testing
