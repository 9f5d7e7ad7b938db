#pragma once
// A simulated spray bar for evaluation: takes the scheduler's open masks
// (a NozzleSink), opens each valve a true latency after its command, and —
// given the vehicle's true pose track — reports every shot with the ground
// path its nozzle sprayed (field frame), for scoring against plant truth.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/treatment/nozzle_scheduler.h"

namespace plantscale::treatment {

struct FieldPose {
  int64_t utime = 0;
  double x_m = 0.0, y_m = 0.0;
  double heading_rad = 0.0;  // of the vehicle's forward axis from the field y axis, CCW
};

// Vehicle-frame point to the field frame (inverse of sim::FieldToVehicle).
Eigen::Vector2d VehicleToField(const FieldPose& pose, const Eigen::Vector2d& vehicle_m);
// Linear interpolation of a time-ordered track; clamps at its ends.
FieldPose Interpolate(std::span<const FieldPose> track, int64_t utime);

struct Shot {
  int nozzle = 0;
  int64_t open_utime = 0;   // on the ground (command + latency)
  int64_t close_utime = 0;
  double width_m = 0.0;     // across the nozzle's path
  std::vector<Eigen::Vector2d> path_field_m;  // nozzle centre, sampled every tick
};

class SimulatedBar {
 public:
  SimulatedBar(const SprayBarOptions& bar, double true_latency_s, double tick_s);

  void Command(int64_t utime, uint64_t open_mask);
  NozzleSink Sink() {
    return [this](int64_t utime, uint64_t mask) { Command(utime, mask); };
  }
  // Shots still open at the end close at the last command.
  std::vector<Shot> Shots(std::span<const FieldPose> track) const;
  int commands() const { return static_cast<int>(commands_.size()); }

 private:
  struct Command_ {
    int64_t utime;
    uint64_t mask;
  };
  SprayBarOptions bar_;
  int64_t latency_us_ = 0;
  int64_t tick_us_ = 0;
  std::vector<Command_> commands_;
};

}  // namespace plantscale::treatment
