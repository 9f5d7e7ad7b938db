#include "engine/motion/mosaic.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "engine/common/check.h"

namespace plantscale::motion {

void FillBlob(const vision::Blob& blob, uint8_t value, cv::Mat& labels) {
  if (blob.contour.empty()) return;
  const cv::Point* points = blob.contour.data();
  const int count = static_cast<int>(blob.contour.size());
  cv::fillPoly(labels, &points, &count, 1, cv::Scalar(value), cv::LINE_8);
}

MosaicGrid MosaicGrid::Covering(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m,
                                double resolution_m) {
  MosaicGrid g;
  g.resolution_m = resolution_m;
  const double x0 = std::floor(min_m.x() / resolution_m);
  const double y0 = std::floor(min_m.y() / resolution_m);
  g.origin_m = {x0 * resolution_m, y0 * resolution_m};
  g.cols = static_cast<int>(std::floor(max_m.x() / resolution_m) - x0) + 1;
  g.rows = static_cast<int>(std::floor(max_m.y() / resolution_m) - y0) + 1;
  return g;
}

MosaicCell MosaicGrid::CellAt(const Eigen::Vector2d& point_m) const {
  const Eigen::Vector2d local = (point_m - origin_m) / resolution_m;
  return {static_cast<int>(std::floor(local.x())), static_cast<int>(std::floor(local.y()))};
}

Eigen::Vector2d MosaicGrid::CellCentre(const MosaicCell& cell) const {
  return origin_m + resolution_m * Eigen::Vector2d(cell.col + 0.5, cell.row + 0.5);
}

bool MosaicGrid::Contains(const MosaicCell& cell) const {
  return cell.col >= 0 && cell.row >= 0 && cell.col < cols && cell.row < rows;
}

size_t MosaicGrid::Index(const MosaicCell& cell) const {
  PLANTSCALE_CHECK(Contains(cell), "cell outside the mosaic grid");
  return static_cast<size_t>(cell.row) * static_cast<size_t>(cols) + static_cast<size_t>(cell.col);
}

uint8_t MosaicMap::LabelAt(const Eigen::Vector2d& point_m) const {
  if (!point_m.allFinite()) return kUnknownLabel;
  const MosaicCell cell = grid.CellAt(point_m);
  return grid.Contains(cell) ? labels[grid.Index(cell)] : kUnknownLabel;
}

OptionErrors MosaicOptions::Validate() const {
  OptionErrors e;
  RequirePositive(e, "resolution_m", resolution_m);
  RequireFinite(e, "min_m.x", min_m.x());
  RequireFinite(e, "min_m.y", min_m.y());
  RequireFinite(e, "max_m.x", max_m.x());
  RequireFinite(e, "max_m.y", max_m.y());
  if (!(max_m.array() > min_m.array()).all()) e.push_back({"max_m", "must exceed min_m"});
  if (e.empty()) {
    // 2^15 cells a side (655 m at 2 cm): the limit of the map grid app/ exports to.
    const Eigen::Array2d cells =
        (max_m / resolution_m).array().floor() - (min_m / resolution_m).array().floor() + 1.0;
    if ((cells > 32768.0).any()) {
      e.push_back({"max_m", "more than 32768 cells a side at resolution_m"});
    }
  }
  RequireNonNegative(e, "plane_height_m", plane_height_m);
  RequireNonNegative(e, "min_plant_cells", min_plant_cells);
  return e;
}

Mosaic::Mosaic(const MosaicOptions& options, const geometry::CameraModel& camera)
    : options_((ThrowIfInvalid("MosaicOptions", options.Validate()), options)), camera_(camera),
      grid_(MosaicGrid::Covering(options.min_m, options.max_m, options.resolution_m)),
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
  const MosaicCell c0 = grid_.CellAt(lo), c1 = grid_.CellAt(hi);
  for (int row = std::max(0, c0.row); row <= std::min(grid_.rows - 1, c1.row); ++row) {
    for (int col = std::max(0, c0.col); col <= std::min(grid_.cols - 1, c1.col); ++col) {
      const MosaicCell cell{col, row};
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

MosaicMap Mosaic::Build() const {
  MosaicMap map;
  map.grid = grid_;
  map.frames = frames_;
  map.labels.assign(grid_.size(), kUnknownLabel);
  cv::Mat plants(grid_.rows, grid_.cols, CV_8UC1, cv::Scalar(0));
  cv::Mat unknown(grid_.rows, grid_.cols, CV_8UC1, cv::Scalar(255));
  for (int row = 0; row < grid_.rows; ++row) {
    for (int col = 0; col < grid_.cols; ++col) {
      const size_t i = grid_.Index({col, row});
      const auto& v = votes_[i];
      if (v[0] + v[1] + v[2] == 0) continue;
      unknown.at<uint8_t>(row, col) = 0;
      const auto best = std::max_element(v.begin(), v.end()) - v.begin();
      map.labels[i] = static_cast<uint8_t>(best);
      if (best == kPlantLabel) plants.at<uint8_t>(row, col) = 255;
    }
  }
  cv::Mat component, stats, centroids;
  const int n = cv::connectedComponentsWithStats(plants, component, stats, centroids, 8, CV_32S);
  cv::dilate(unknown, unknown, cv::Mat());
  std::vector<uint8_t> truncated(static_cast<size_t>(n), 0);
  for (int r = 0; r < component.rows; ++r) {
    for (int c = 0; c < component.cols; ++c) {
      if (unknown.at<uint8_t>(r, c) != 0) truncated[component.at<int>(r, c)] = 1;
    }
  }
  const double res = grid_.resolution_m;
  for (int k = 1; k < n; ++k) {
    const int area = stats.at<int>(k, cv::CC_STAT_AREA);
    if (area < options_.min_plant_cells || truncated[k]) continue;
    MosaicPlant plant;
    plant.position_m = grid_.origin_m + res * Eigen::Vector2d(centroids.at<double>(k, 0) + 0.5,
                                                              centroids.at<double>(k, 1) + 0.5);
    plant.radius_m = std::sqrt(area / M_PI) * res;
    map.plants.push_back(plant);
  }
  return map;
}

}  // namespace plantscale::motion
