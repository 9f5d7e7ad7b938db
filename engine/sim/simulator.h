#pragma once
// The embedded default when no camera is attached: a field, a vehicle and a
// camera, advanced frame by frame with complete ground truth (docs/simulator.md).
// Seeded: the same options and seed give the same bytes.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/grid_model.h"
#include "engine/sim/field.h"
#include "engine/sim/renderer.h"
#include "engine/sim/vehicle.h"

namespace plantscale::sim {

struct SimulatorOptions {
  std::string preset = "custom";
  geometry::CameraOptions camera;
  geometry::GridModelOptions grid;
  FieldOptions field;
  VehicleOptions vehicle;
  RenderOptions render;
  double length_m = 40.0;  // distance driven
  uint64_t seed = 1;

  // Keys are prefixed with the section: "camera.height_m", "field.rows", ...
  OptionErrors Validate() const;
};

struct PlantTruth {
  int instance = 0;  // value of the plant's pixels in the instance image
  int plant_id = 0;
  PlantClass cls = PlantClass::kCrop;
  int row = 0;
  int line = -1;
  Eigen::Vector2d field_m{0.0, 0.0};
  Eigen::Vector2d vehicle_m{0.0, 0.0};
  double radius_m = 0.0;
  double height_m = 0.0;
  std::optional<Eigen::Vector2d> root_px;  // projection of the root (ground)
  int area_px = 0;
  Eigen::Vector2d centroid_px{0.0, 0.0};
};

struct FrameTruth {
  int index = 0;
  int64_t utime = 0;
  Pose2 pose;
  CameraBounce bounce;
  double distance_m = 0.0;
  geometry::GridState grid;  // (t_x, Y, Ψ, r̄, l̄) against the planted grid
  int line0 = -1;            // field line index of grid line m = 0
  std::vector<PlantTruth> plants;
};

struct SimFrame {
  FrameTruth truth;
  RenderedFrame rendered;
  std::vector<OdometrySample> odometry;  // samples since the previous frame
};

class Simulator {
 public:
  // Throws InvalidOptionsError naming the offending keys.
  explicit Simulator(const SimulatorOptions& options);

  // Advances to the next captured frame; false once the pass is driven.
  // With render = false only the pose, odometry and grid truth are filled
  // (no image, no plant truth); later frames are the same bytes either way.
  bool Next(SimFrame& frame, bool render = true);

  const SimulatorOptions& options() const { return options_; }
  const Field& field() const { return field_; }
  const geometry::CameraModel& camera() const { return camera_; }
  int expected_frames() const;
  int dropped_frames() const { return dropped_; }
  // The camera as it was with `bounce` (a frame's truth.bounce): what
  // placed that frame's pixels, for scoring against the truth.
  geometry::CameraModel CameraFor(const CameraBounce& bounce) const;

 private:
  void FillGridTruth(FrameTruth& truth) const;
  void FillPlantTruth(const geometry::CameraModel& camera, const RenderedFrame& rendered,
                      FrameTruth& truth) const;

  SimulatorOptions options_;
  geometry::CameraModel camera_;
  Field field_;
  Vehicle vehicle_;
  Renderer renderer_;
  Rng timing_rng_;
  int frame_index_ = 0;  // frames due so far, dropped or not
  int emitted_ = 0;
  int dropped_ = 0;
};

}  // namespace plantscale::sim
