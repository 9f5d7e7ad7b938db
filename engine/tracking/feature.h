#pragma once
// What the tracker sees of a segmented blob (engine/vision) — kept as its own
// small type so that tracking does not depend on how blobs were found.

#include <Eigen/Core>

namespace plantscale::tracking {

struct Feature {
  Eigen::Vector2d ground_m{0.0, 0.0};  // centroid on the virtual ground plane, vehicle frame
  Eigen::Vector2d image_px{0.0, 0.0};  // centroid in the image (first pixel's centre 0.5)
  double area_m2 = 0.0;                // ground area
  bool clipped = false;                // touches the image border: centroid biased inward
  // Image bounding box [u0, u1) × [v0, v1) (all 0: unknown).
  double box_u0_px = 0.0, box_v0_px = 0.0, box_u1_px = 0.0, box_v1_px = 0.0;
  // The blob's major axis on the ground at its centroid: the image's major
  // axis carried by the located plane's Jacobian, 2σ long (zero: unknown),
  // and σ_major/σ_minor in the image (0: unknown). Plants touching along a
  // row make one long blob whose axis runs along the row (the initialiser's
  // bands on a closed canopy).
  Eigen::Vector2d axis_m{0.0, 0.0};
  double elongation = 0.0;

  bool BoxHolds(const Eigen::Vector2d& uv) const {
    return uv.x() >= box_u0_px && uv.x() < box_u1_px && uv.y() >= box_v0_px && uv.y() < box_v1_px;
  }
};

}  // namespace plantscale::tracking
