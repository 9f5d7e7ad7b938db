#pragma once
// Writes a simulated pass to disk: frames, label and instance images, and
// ground truth as CSV, into a staging folder that replaces the output folder
// only when everything has been written (nothing is left half-way).

#include <filesystem>
#include <iosfwd>

#include "engine/sim/simulator.h"

namespace plantscale::app {

struct SimulateRequest {
  sim::SimulatorOptions options;
  std::filesystem::path out;
  int image_every = 1;   // write images of every k-th frame (truth for all)
  bool progress = true;  // progress bar on the given stream
};

struct SimulateSummary {
  int frames = 0;
  int dropped = 0;
  int images_written = 0;
  double distance_m = 0.0;
  double odometry_distance_m = 0.0;
  int crops_in_field = 0;
  int weeds_in_field = 0;
  int plants_seen = 0;
  double rms_offset_m = 0.0;
  double max_abs_offset_m = 0.0;
  double max_abs_bearing_rad = 0.0;
  double mean_plant_pixels = 0.0;
  double simulate_seconds = 0.0;  // engine time only, without disk writes
  double wall_seconds = 0.0;
};

// Throws std::runtime_error naming the file on I/O failure.
SimulateSummary RunSimulation(const SimulateRequest& request, std::ostream& progress);

}  // namespace plantscale::app
