#pragma once
// Observation model of the grid tracker (thesis §4.2): where a grid plant
// appears, on the virtual ground plane or in the image, and how uncertain a
// measured centroid is there (eq. 4.28). The plant point model; on the
// filter's full state: plant_point_model.h. The merged-blob strip:
// strip_model.h; height from size: height_from_size.h. Finite-difference
// tests of every Jacobian here: observation_model_test.cc.

#include <Eigen/Core>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/centroid_height.h"
#include "engine/geometry/grid_model.h"
#include "engine/tracking/feature.h"

namespace plantscale::tracking {

struct TrackerOptions;

// Plant (m, n) displaced by its own offset δ = (δ_across, δ_along) in grid
// coordinates: (n r̄ + δ_x, m l̄ + Y + δ_y), rotated by Ψ and offset by t_x
// into the vehicle frame (eqs. 2.1–2.2, A.1).
Eigen::Vector2d PlantWithOffset(const geometry::GridState& state, int m, int n,
                                const Eigen::Vector2d& offset);
// d/d(t_x, Y, Ψ, r̄, l̄, δ_x, δ_y).
Eigen::Matrix<double, 2, 7> PlantWithOffsetJacobian(const geometry::GridState& state, int m, int n,
                                                    const Eigen::Vector2d& offset);

// How a point on the virtual plane (vehicle frame) seen by a camera h_c
// above that plane moves when the camera pitches (about x), rolls (about y)
// or rises, to first order: d(x, y)/d(pitch, roll, height).
Eigen::Matrix<double, 2, 3> BounceJacobian(const Eigen::Vector2d& point, double camera_above_plane_m);
// How a point on the plane z = plane_height_m (vehicle frame) located with
// `camera` moves when the true focal length is (1 + ε) times the camera's:
// its image point moves away from the principal point by ε (uv − c), so
// d(x, y)/dε = ∂(x, y)/∂(u, v) · (uv − c). Zero where the point is not seen.
Eigen::Vector2d FocalJacobian(const geometry::CameraModel& camera, const Eigen::Vector2d& point,
                              double plane_height_m);

struct Prediction {
  Eigen::Vector2d value;
  Eigen::MatrixXd jacobian;           // 2 × state size
  Eigen::MatrixXd offset_jacobian;    // d value / d(δx, δy[, δh]) of this plant
  Eigen::Matrix<double, 2, 3> bounce_jacobian;  // d value / d(pitch, roll, height) of the camera
  Eigen::Vector2d focal_jacobian = Eigen::Vector2d::Zero();  // d value / d(f_true / f − 1)
};

struct Measurement {
  Eigen::Vector2d value;
  Eigen::Matrix2d covariance;
};

class ObservationModel {
 public:
  // heights: where centroids are located (null: on the virtual plane).
  ObservationModel(const geometry::CameraModel& camera, const TrackerOptions& options,
                   const geometry::CentroidHeights* heights = nullptr);

  // x: the filter state (core, then δ pairs); offset_index: where this
  // plant's δ sits in x, or −1 when it has none.
  Prediction Predict(const Eigen::VectorXd& x, const geometry::GridState& state, int m, int n,
                     int offset_index) const;
  Measurement Measure(const Feature& feature) const;
  // Prior variances of a plant's own states: δx, δy, then δh (plant_heights).
  static Eigen::VectorXd PlantPrior(const TrackerOptions& options);
  const TrackerOptions& options() const { return options_; }

 private:
  const geometry::CameraModel& camera_;
  const TrackerOptions& options_;
  // Height above the soil at which a crop centroid at `point` (vehicle
  // frame) is located: the height model's, or the virtual plane.
  double LocatedHeight(const Eigen::Vector2d& point) const;

  const geometry::CentroidHeights* heights_;
};

}  // namespace plantscale::tracking
