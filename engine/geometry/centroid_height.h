#pragma once
// Where a crop plant's image centroid really is (thesis §2.3.8).
//
// The thesis models a cauliflower as an inverted hemisphere of leaves and
// projects blob centroids onto a "virtual ground plane" set by eye at plant
// height. The image centroid of such a plant is not at plant height, and not
// at one height over the view: seen from straight above it is the centroid
// of the rim's disc (the top, z = h); seen obliquely the silhouette gains the
// near side of the bowl, and the centroid's ray crosses the plant's axis
// lower down. A single plane at the wrong height scales every measured
// position about the camera's nadir, which a grid tracker cannot tell from a
// wrong plant spacing or an odometry scale error (a forward drift).
//
// `CentroidHeights` computes, for the same inverted hemisphere the thesis
// uses, the height at which the ray through the silhouette's image centroid
// crosses the plant's vertical axis, for plants over the whole image, and
// locates a blob centroid on that surface instead of on one plane. The
// grower gives the crop's mean leaf span and height (a ruler, or the growth
// stage); nothing is fitted to the images.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"

namespace plantscale::geometry {

// The thesis's inverted hemisphere (§2.3.8, fig. 2.19): the solid
// { z ≤ h, z ≥ h·(1 − √(1 − (ρ/R)²)) } about the plant's root, with the
// root on the soil and the leaf tips at radius R and height h.
struct CropShape {
  double radius_m = 0.14;
  double height_m = 0.11;

  OptionErrors Validate() const;
};

// Whether the ray from `origin` along `direction` (vehicle frame, pointing
// down) passes through the crop solid rooted at `root`. Exact: along the
// ray the solid's inequality is a concave quadratic in z.
bool RayHitsCrop(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                 const Eigen::Vector2d& root, const CropShape& shape);

// The height at which the ray through the image centroid of the silhouette
// of a plant rooted at `root` (vehicle frame) crosses the plant's axis;
// nullopt when the plant is not wholly in front of the camera. The
// silhouette is sampled on a grid of `samples` × `samples` pixels' worth
// over its image bounding box (equal image area per sample, as a blob's
// pixel centroid weighs it).
std::optional<double> SilhouetteCentroidHeight(const CameraModel& camera,
                                               const Eigen::Vector2d& root, const CropShape& shape,
                                               int samples = 40);

struct CentroidHeightOptions {
  CropShape shape;
  double node_spacing_px = 24.0;  // table nodes over the image
  int samples = 32;

  OptionErrors Validate() const;
};

// A table of SilhouetteCentroidHeight over the image, indexed by where the
// centroid appears (bilinear between nodes), and the blob centroid located
// on that height.
class CentroidHeights {
 public:
  // Throws InvalidOptionsError.
  CentroidHeights(const CameraModel& camera, const CentroidHeightOptions& options);

  // Height of the centroid of a crop plant whose image centroid is at uv.
  double HeightAt(const Eigen::Vector2d& uv) const;
  // The plant's axis position: uv's ray met at HeightAt(uv); nullopt above
  // the horizon.
  std::optional<Eigen::Vector2d> Locate(const Eigen::Vector2d& uv) const;
  // d Locate / d(uv), the height held fixed (its change over a pixel is
  // negligible beside the ray's).
  Eigen::Matrix2d LocateJacobian(const Eigen::Vector2d& uv) const;
  const CentroidHeightOptions& options() const { return options_; }

 private:
  double NodeHeight(const Eigen::Vector2d& uv) const;

  CameraModel camera_;
  CentroidHeightOptions options_;
  int columns_ = 0;
  int rows_ = 0;
  std::vector<double> heights_;  // rows_ × columns_, row-major
};

}  // namespace plantscale::geometry
