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
};

}  // namespace plantscale::tracking
