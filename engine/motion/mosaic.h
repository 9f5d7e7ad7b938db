#pragma once
// The field mosaic (Sanchiz & Pla §5): every frame's plant/weed/soil labels
// placed on the ground with the recovered pose; a cell's class is the
// majority of the votes it received. Built as a MosaicMap in the first
// frame's vehicle frame (x right, y forward), with the plant blobs of the
// voted map as plants. MosaicMap is the engine's own value type (the engine
// does not depend on maps/); app/mosaic_map.h turns it into a maps::CropMap
// for the exporters.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/motion/planar_motion.h"
#include "engine/vision/blobs.h"

namespace plantscale::motion {

// Label values of a classified frame and of the mosaic's cells (the values
// of maps::CellClass, which app/mosaic_map.cc asserts). Unknown: no votes.
inline constexpr uint8_t kSoilLabel = 0, kPlantLabel = 1, kWeedLabel = 2, kUnknownLabel = 3;

// Labels of one frame: mask pixels inside the outline of a blob that
// `is_plant` accepts are plant, other mask pixels weed, the rest soil.
template <typename IsPlant>
void LabelFrame(const cv::Mat& mask, std::span<const vision::Blob> blobs, IsPlant is_plant,
                cv::Mat& labels);
void FillBlob(const vision::Blob& blob, uint8_t value, cv::Mat& labels);

struct MosaicCell {
  int col = 0;
  int row = 0;
};

// Square cells of resolution_m; cell (col, row) covers
//   x ∈ [origin_x + col·res, origin_x + (col+1)·res),
//   y ∈ [origin_y + row·res, origin_y + (row+1)·res),
// stored row-major with row 0 at the smallest y (maps::MapGrid's layout).
struct MosaicGrid {
  double resolution_m = 0.01;
  Eigen::Vector2d origin_m{0.0, 0.0};  // corner of cell (0, 0)
  int cols = 0;
  int rows = 0;

  // The smallest grid of cells aligned on multiples of the resolution that
  // covers [min, max].
  static MosaicGrid Covering(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m,
                             double resolution_m);
  size_t size() const { return static_cast<size_t>(cols) * static_cast<size_t>(rows); }
  // Cell containing a point (floor); no bounds check.
  MosaicCell CellAt(const Eigen::Vector2d& point_m) const;
  Eigen::Vector2d CellCentre(const MosaicCell& cell) const;
  bool Contains(const MosaicCell& cell) const;
  // Row-major index of a cell inside the grid: row·cols + col.
  size_t Index(const MosaicCell& cell) const;
};

struct MosaicPlant {
  Eigen::Vector2d position_m{0.0, 0.0};  // centroid of the blob's cells
  double radius_m = 0.0;                 // of the disc of the blob's area
};

struct MosaicMap {
  MosaicGrid grid;
  std::vector<uint8_t> labels;      // per cell (grid.Index): k*Label
  std::vector<MosaicPlant> plants;  // in the order of the voted map's components
  int frames = 0;                   // frames added

  // Label of the cell containing a point; unknown outside the grid.
  uint8_t LabelAt(const Eigen::Vector2d& point_m) const;
};

struct MosaicOptions {
  double resolution_m = 0.01;
  Eigen::Vector2d min_m{-1.0, -1.0};  // extent, first frame's vehicle frame
  Eigen::Vector2d max_m{1.0, 10.0};
  double plane_height_m = 0.0;        // plane the labels are placed on
  int min_plant_cells = 20;           // smaller plant components are not registered

  OptionErrors Validate() const;
};

class Mosaic {
 public:
  Mosaic(const MosaicOptions& options, const geometry::CameraModel& camera);

  // Votes every cell of the frame's footprint with the label under it.
  void AddFrame(const cv::Mat& labels, const VehiclePose2& pose);
  // Majority vote per cell (cells without votes stay unknown) and the plant
  // components as plants, except those touching unobserved cells (plants
  // cut by the edge of every view: their centres would be biased inwards).
  MosaicMap Build() const;
  int frames() const { return frames_; }

 private:
  MosaicOptions options_;
  geometry::CameraModel camera_;
  MosaicGrid grid_;
  Eigen::Matrix3d plane_to_image_;
  std::vector<std::array<uint16_t, 3>> votes_;
  int frames_ = 0;
};

template <typename IsPlant>
void LabelFrame(const cv::Mat& mask, std::span<const vision::Blob> blobs, IsPlant is_plant,
                cv::Mat& labels) {
  labels.create(mask.size(), CV_8UC1);
  labels.setTo(cv::Scalar(kWeedLabel), mask);
  labels.setTo(cv::Scalar(kSoilLabel), mask == 0);
  for (const vision::Blob& b : blobs) {
    if (is_plant(b)) FillBlob(b, kPlantLabel, labels);
  }
  labels.setTo(cv::Scalar(kSoilLabel), mask == 0);
}

}  // namespace plantscale::motion
