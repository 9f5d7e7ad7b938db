#pragma once
// Test-only: the field's observation model and a central difference, for
// the observation models' finite-difference tests.

#include <Eigen/Core>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/centroid_height.h"
#include "engine/geometry/test_cameras.h"
#include "engine/tracking/observation_model.h"
#include "engine/tracking/tracker_options.h"

namespace plantscale::tracking::testing {

// The field's camera (virtual plane 0.1 m) and a crop of 0.14 m leaf-tip
// radius with its tips at 0.112 m: centroids located on its heights.
struct FieldObservation {
  geometry::CameraModel camera{[] {
    geometry::CameraOptions co = geometry::testing::ThesisCamera();
    co.virtual_plane_height_m = 0.1;
    return co;
  }()};
  geometry::CentroidHeights heights{camera, [] {
                                      geometry::CentroidHeightOptions ho;
                                      ho.shape = {0.14, 0.112};
                                      return ho;
                                    }()};
  TrackerOptions options;
  ObservationModel model{camera, options, &heights};
};

// The central difference of f (a vector or a number) at x along state i.
template <typename F>
auto CentralDifference(const F& f, const Eigen::VectorXd& x, int i) {
  const double h = 1e-6;
  Eigen::VectorXd hi = x;
  Eigen::VectorXd lo = x;
  hi(i) += h;
  lo(i) -= h;
  using Value = decltype(f(x));
  const Value d = (f(hi) - f(lo)) / (2 * h);
  return d;
}

}  // namespace plantscale::tracking::testing
