#pragma once
// The field mosaic (Sanchiz & Pla §5): every frame's plant/weed/soil labels
// placed on the ground with the recovered pose; a cell's class is the
// majority of the votes it received. Stored as a maps::CropMap in the
// first frame's vehicle frame (x right, y forward), with the plant blobs of
// the voted map registered as plants.

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/motion/planar_motion.h"
#include "engine/vision/blobs.h"
#include "maps/crop_map.h"

namespace plantscale::motion {

// Label values of a classified frame (those of maps::CellClass).
inline constexpr uint8_t kSoilLabel = 0, kPlantLabel = 1, kWeedLabel = 2;

// Labels of one frame: mask pixels inside the outline of a blob that
// `is_plant` accepts are plant, other mask pixels weed, the rest soil.
template <typename IsPlant>
void LabelFrame(const cv::Mat& mask, std::span<const vision::Blob> blobs, IsPlant is_plant,
                cv::Mat& labels);
void FillBlob(const vision::Blob& blob, uint8_t value, cv::Mat& labels);

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
  maps::CropMap Build() const;
  int frames() const { return frames_; }

 private:
  MosaicOptions options_;
  geometry::CameraModel camera_;
  maps::MapGrid grid_;
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
