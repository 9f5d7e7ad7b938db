#include "engine/motion/mosaic.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace plantscale::motion {

void FillBlob(const vision::Blob& blob, uint8_t value, cv::Mat& labels) {
  if (blob.contour.empty()) return;
  const cv::Point* points = blob.contour.data();
  const int count = static_cast<int>(blob.contour.size());
  cv::fillPoly(labels, &points, &count, 1, cv::Scalar(value), cv::LINE_8);
}

OptionErrors MosaicOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "resolution_m", resolution_m);
  if (!(max_m.array() > min_m.array()).all()) e.push_back({"max_m", "must exceed min_m"});
  RequireNonNegative(e, "plane_height_m", plane_height_m);
  RequireNonNegative(e, "min_plant_cells", min_plant_cells);
  return e;
}

Mosaic::Mosaic(const MosaicOptions& options, const geometry::CameraModel& camera)
    : options_((ThrowIfInvalid("MosaicOptions", options.Validate()), options)), camera_(camera),
      grid_(maps::MapGrid::Covering(options.min_m, options.max_m, options.resolution_m)),
      plane_to_image_(camera.PlaneToImageHomography(options.plane_height_m)),
      votes_(grid_.size(), {0, 0, 0}) {}

void Mosaic::AddFrame(const cv::Mat& labels, const VehiclePose2& pose) {
  ++frames_;
  // Footprint: the image corners on the plane, in the world.
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  const double w = camera_.width(), h = camera_.height();
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0),
                                   Eigen::Vector2d(0, h), Eigen::Vector2d(w, h)}) {
    const auto g = camera_.ImageToPlane(uv, options_.plane_height_m);
    if (!g) return;  // a horizon in view: not a ground-looking frame
    const Eigen::Vector2d world = pose.ToWorld(*g);
    lo = lo.cwiseMin(world);
    hi = hi.cwiseMax(world);
  }
  const maps::Cell c0 = grid_.CellAt(lo), c1 = grid_.CellAt(hi);
  for (int row = std::max(0, c0.row); row <= std::min(grid_.rows() - 1, c1.row); ++row) {
    for (int col = std::max(0, c0.col); col <= std::min(grid_.cols() - 1, c1.col); ++col) {
      const maps::Cell cell{col, row};
      const Eigen::Vector2d p = pose.FromWorld(grid_.CellCentre(cell));
      const Eigen::Vector3d uvw = plane_to_image_ * p.homogeneous();
      if (uvw.z() <= 0.0) continue;
      const Eigen::Vector2d uv = uvw.hnormalized();
      if (!camera_.InImage(uv)) continue;
      const uint8_t label = labels.at<uint8_t>(static_cast<int>(uv.y()), static_cast<int>(uv.x()));
      if (label <= kWeedLabel) {
        auto& v = votes_[grid_.Index(cell)][label];
        if (v < UINT16_MAX) ++v;
      }
    }
  }
}

maps::CropMap Mosaic::Build() const {
  maps::CropMap map(grid_);
  maps::MapLayers layers = map.layers();
  cv::Mat plants(grid_.rows(), grid_.cols(), CV_8UC1, cv::Scalar(0));
  cv::Mat unknown(grid_.rows(), grid_.cols(), CV_8UC1, cv::Scalar(255));
  for (size_t i = 0; i < votes_.size(); ++i) {
    const auto& v = votes_[i];
    if (v[0] + v[1] + v[2] == 0) continue;
    unknown.at<uint8_t>(grid_.CellOf(i).row, grid_.CellOf(i).col) = 0;
    const auto best = std::max_element(v.begin(), v.end()) - v.begin();
    layers.cls[i] = static_cast<uint8_t>(best);  // CellClass has the label values
    if (best == kPlantLabel) plants.at<uint8_t>(grid_.CellOf(i).row, grid_.CellOf(i).col) = 255;
  }
  map.SetLayers(std::move(layers));
  cv::Mat component, stats, centroids;
  const int n = cv::connectedComponentsWithStats(plants, component, stats, centroids, 8, CV_32S);
  cv::dilate(unknown, unknown, cv::Mat());
  std::vector<uint8_t> truncated(static_cast<size_t>(n), 0);
  for (int r = 0; r < component.rows; ++r) {
    for (int c = 0; c < component.cols; ++c) {
      if (unknown.at<uint8_t>(r, c) != 0) truncated[component.at<int>(r, c)] = 1;
    }
  }
  int64_t id = 1;
  for (int k = 1; k < n; ++k) {
    const int area = stats.at<int>(k, cv::CC_STAT_AREA);
    if (area < options_.min_plant_cells || truncated[k]) continue;
    maps::MapPlant plant;
    plant.id = id++;
    const double res = grid_.resolution_m();
    plant.position_m = grid_.origin_m() + res * Eigen::Vector2d(centroids.at<double>(k, 0) + 0.5,
                                                                centroids.at<double>(k, 1) + 0.5);
    plant.kind = maps::PlantKind::kCrop;
    plant.radius_m = std::sqrt(area / M_PI) * res;
    plant.why = "mosaic plant blob";
    map.AddPlant(plant);
  }
  map.SetMetadata("source", "motion mosaic (Sanchiz & Pla majority vote)");
  map.SetMetadata("frames", std::to_string(frames_));
  return map;
}

}  // namespace plantscale::motion
