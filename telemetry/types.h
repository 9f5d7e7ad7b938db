#pragma once
// Plain telemetry-side value types for what the engine will produce once
// tracking (issue 5), classification and treatment (issue 6) and the maps
// exist. Conversions (convert.h) map these to LCM messages; when the engine
// types land, conversions from them replace these structs here, in
// telemetry/, never in engine/.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/geometry/grid_model.h"

namespace plantscale::telemetry {

enum class FilterMode : int8_t {
  kInitialising = 0,
  kTracking = 1,
  kDeadReckoning = 2,
  kLost = 3,
  kTruth = 4
};

// The tracker's estimate for one frame (thesis §4.1.2) with its statistics.
struct GridEstimate {
  int64_t utime = 0;
  int frame_index = 0;
  geometry::GridState state;
  geometry::Matrix5d covariance = geometry::Matrix5d::Zero();
  FilterMode mode = FilterMode::kInitialising;
  std::vector<int> lines_in_view;
  int observations = 0;
  int validated = 0;
  double innovation_nis = 0.0;
  double innovation_rms_px = 0.0;
};

enum class PlantKind : int8_t { kUnknown = 0, kCrop = 1, kWeed = 2 };

struct PlantObservation {
  int64_t id = 0;
  PlantKind kind = PlantKind::kUnknown;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  // field frame
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  double size_m2 = 0.0;
  bool sprayed = false;
  int why = 0;  // plantscale_plant_t::WHY_*
  double distance_to_crop_m = 0.0;
};

// A changed map tile: width × height cells, one byte each, row-major.
struct MapTileDelta {
  int tile_x = 0;
  int tile_y = 0;
  int revision = 0;
  Eigen::Vector2d origin_m = Eigen::Vector2d::Zero();
  double resolution_m = 0.01333;
  int width = 0;
  int height = 0;
  std::vector<uint8_t> cells;
};

struct NozzleShot {
  int nozzle = 0;
  int64_t open_utime = 0;
  int64_t close_utime = 0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int64_t plant_id = -1;
};

struct NozzleBar {
  std::vector<bool> open;
  std::vector<int> fault;  // plantscale_nozzles_t::FAULT_*, one per nozzle
  bool failsafe = true;
  std::vector<NozzleShot> shots;  // since the previous message
};

struct Pose {
  double x_m = 0.0;
  double y_m = 0.0;
  double heading_rad = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

struct Health {
  std::string source;
  int64_t boot_utime = 0;
  double frame_rate_hz = 0.0;
  int frames = 0;
  int dropped_frames = 0;
  double distance_m = 0.0;
  bool failsafe = true;
  std::vector<std::string> faults;
  int64_t telemetry_dropped = 0;
};

}  // namespace plantscale::telemetry
