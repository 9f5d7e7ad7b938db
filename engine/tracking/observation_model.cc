#include "engine/tracking/observation_model.h"

#include <cmath>

#include "engine/tracking/tracker_options.h"

namespace plantscale::tracking {

using geometry::GridState;

Eigen::Vector2d PlantWithOffset(const GridState& s, int m, int n, const Eigen::Vector2d& d) {
  const double c = std::cos(s.bearing_rad);
  const double si = std::sin(s.bearing_rad);
  const double gx = n * s.row_spacing_m + d.x();
  const double gy = m * s.plant_spacing_m + s.forward_m + d.y();
  return {c * gx + si * gy + s.offset_m, -si * gx + c * gy};
}

Eigen::Matrix<double, 2, 7> PlantWithOffsetJacobian(const GridState& s, int m, int n,
                                                    const Eigen::Vector2d& d) {
  const double c = std::cos(s.bearing_rad);
  const double si = std::sin(s.bearing_rad);
  const double gx = n * s.row_spacing_m + d.x();
  const double gy = m * s.plant_spacing_m + s.forward_m + d.y();
  Eigen::Matrix<double, 2, 7> j;
  //     t_x  Y    Ψ                  r̄       l̄       δx   δy
  j << 1.0, si, -si * gx + c * gy, c * n, si * m, c, si,  //
      0.0, c, -c * gx - si * gy, -si * n, c * m, -si, c;
  return j;
}

Eigen::Matrix<double, 2, 3> BounceJacobian(const Eigen::Vector2d& p, double hc) {
  // Rays from the camera (0, 0, h_c) through (x, y, 0): a pitch ε turns
  // (y, −h_c) into (y + ε h_c, −h_c + ε y), a roll turns (x, −h_c) into
  // (x − ε h_c, −h_c − ε x); a rise shrinks the point towards the nadir.
  const double x = p.x();
  const double y = p.y();
  Eigen::Matrix<double, 2, 3> j;
  j << x * y / hc, -(hc + x * x / hc), -x / hc,  //
      hc + y * y / hc, -x * y / hc, -y / hc;
  return j;
}

Eigen::Vector2d FocalJacobian(const geometry::CameraModel& camera, const Eigen::Vector2d& p,
                              double plane) {
  const auto uv = camera.Project({p.x(), p.y(), plane});
  if (!uv) return Eigen::Vector2d::Zero();
  return camera.ImageToPlaneJacobian(*uv, plane) * (*uv - camera.principal_point());
}

ObservationModel::ObservationModel(const geometry::CameraModel& camera,
                                   const TrackerOptions& options,
                                   const geometry::CentroidHeights* heights)
    : camera_(camera), options_(options), heights_(heights) {}

Eigen::VectorXd ObservationModel::PlantPrior(const TrackerOptions& o) {
  const double offset = o.plant_offset_sd_m * o.plant_offset_sd_m;
  if (!o.PlantHeightStates()) return Eigen::Vector2d(offset, offset);
  return Eigen::Vector3d(offset, offset, o.plant_height_sd_m * o.plant_height_sd_m);
}

double ObservationModel::LocatedHeight(const Eigen::Vector2d& point) const {
  const double plane = camera_.options().virtual_plane_height_m;
  if (!heights_) return plane;
  const auto uv = camera_.Project({point.x(), point.y(), plane});
  return uv ? heights_->HeightAt(*uv) : plane;
}

Prediction ObservationModel::Predict(const Eigen::VectorXd& x, const GridState& s, int m, int n,
                                     int offset_index) const {
  const int core = options_.estimate_spacing ? 5 : 3;
  const int own = options_.PlantHeightStates() ? 3 : 2;
  const Eigen::Vector2d delta =
      offset_index >= 0 ? Eigen::Vector2d(x.segment<2>(offset_index)) : Eigen::Vector2d::Zero();
  const Eigen::Vector2d g = PlantWithOffset(s, m, n, delta);
  const Eigen::Matrix<double, 2, 7> jg = PlantWithOffsetJacobian(s, m, n, delta);
  // The plant's centroid stands δh above the height it is located at, h_l:
  // its ray meets h_l at g·(H − h_l)/(H − h_l − δh), radially from the nadir.
  double scale = 1.0;
  Eigen::Vector2d d_height = Eigen::Vector2d::Zero();
  if (options_.PlantHeightStates()) {
    const double above = camera_.options().height_m - LocatedHeight(g);
    const double dh = offset_index >= 0 ? x(offset_index + 2) : 0.0;
    scale = above / (above - dh);
    d_height = g * (above / ((above - dh) * (above - dh)));
  }
  Prediction p;
  p.jacobian = Eigen::MatrixXd::Zero(2, x.size());
  p.jacobian.leftCols(core) = scale * jg.leftCols(core);
  p.offset_jacobian = Eigen::MatrixXd(2, own);
  p.offset_jacobian.leftCols<2>() = scale * jg.rightCols<2>();
  if (options_.PlantHeightStates()) p.offset_jacobian.col(2) = d_height;
  if (offset_index >= 0) p.jacobian.middleCols(offset_index, own) = p.offset_jacobian;
  p.value = scale * g;
  const double hc = camera_.options().height_m - camera_.options().virtual_plane_height_m;
  p.bounce_jacobian = BounceJacobian(p.value, hc);
  if (options_.CalibrationStates()) {
    p.focal_jacobian = FocalJacobian(camera_, p.value, camera_.options().virtual_plane_height_m);
  }
  if (options_.space == ObservationSpace::kImage) {
    const Eigen::Vector3d ground(g.x(), g.y(), camera_.options().virtual_plane_height_m);
    const auto uv = camera_.Project(ground);
    const Eigen::Matrix2d d_uv = camera_.ProjectJacobian(ground).leftCols<2>();
    p.value = uv ? *uv : Eigen::Vector2d(NAN, NAN);
    p.jacobian = d_uv * p.jacobian;
    p.offset_jacobian = d_uv * p.offset_jacobian;
    p.bounce_jacobian = d_uv * p.bounce_jacobian;
    p.focal_jacobian = d_uv * p.focal_jacobian;
  }
  return p;
}

Measurement ObservationModel::Measure(const Feature& f) const {
  const double plane = camera_.options().virtual_plane_height_m;
  const double rw = options_.feature_sd_m * options_.feature_sd_m;
  const double rp = options_.pixel_sd_px * options_.pixel_sd_px;
  Measurement z;
  if (options_.space == ObservationSpace::kImage) {
    // Thesis eq. 4.28: R_w projected into the image at the feature.
    const Eigen::Matrix2d fw =
        camera_.ProjectJacobian({f.ground_m.x(), f.ground_m.y(), plane}).leftCols<2>();
    z.value = f.image_px;
    z.covariance = rw * fw * fw.transpose() + rp * Eigen::Matrix2d::Identity();
  } else {
    const Eigen::Matrix2d jp = heights_ ? heights_->LocateJacobian(f.image_px)
                                        : camera_.ImageToPlaneJacobian(f.image_px, plane);
    z.value = f.ground_m;
    z.covariance = rw * Eigen::Matrix2d::Identity() + rp * jp * jp.transpose();
  }
  return z;
}

}  // namespace plantscale::tracking
