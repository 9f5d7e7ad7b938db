#include "engine/geometry/camera_model.h"

#include <cmath>
#include <numbers>

namespace plantscale::geometry {
namespace {

// Camera axes for a camera tilted `tilt` below the horizontal (thesis A.1
// with Ψ = 0 and φ = 90° − tilt): x right, y down the image, z forward.
Eigen::Matrix3d TiltRotation(double tilt) {
  const double c = std::cos(tilt);
  const double s = std::sin(tilt);
  Eigen::Matrix3d r;
  r << 1.0, 0.0, 0.0,  //
      0.0, -s, -c,     //
      0.0, c, -s;
  return r;
}

// Rotation of the vehicle body about its forward (y) axis by `roll`.
Eigen::Matrix3d RollRotation(double roll) {
  const double c = std::cos(roll);
  const double s = std::sin(roll);
  Eigen::Matrix3d r;
  r << c, 0.0, s,     //
      0.0, 1.0, 0.0,  //
      -s, 0.0, c;
  return r;
}

}  // namespace

OptionErrors CameraOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "height_m", height_m);
  RequireInRange(errors, "tilt_rad", tilt_rad, 0.0, std::numbers::pi / 2.0, false, true);
  RequireInRange(errors, "roll_rad", roll_rad, -0.5, 0.5);
  RequirePositive(errors, "focal_length_m", focal_length_m);
  RequirePositive(errors, "pixel_width_m", pixel_width_m);
  RequirePositive(errors, "pixel_height_m", pixel_height_m);
  if (image_width_px <= 0) errors.push_back({"image_width_px", "must be > 0"});
  if (image_height_px <= 0) errors.push_back({"image_height_px", "must be > 0"});
  if (principal_point_u_px) RequireFinite(errors, "principal_point_u_px", *principal_point_u_px);
  if (principal_point_v_px) RequireFinite(errors, "principal_point_v_px", *principal_point_v_px);
  RequireNonNegative(errors, "virtual_plane_height_m", virtual_plane_height_m);
  if (std::isfinite(height_m) && height_m > 0.0 && virtual_plane_height_m >= height_m) {
    errors.push_back({"virtual_plane_height_m", "must be below the camera height"});
  }
  return errors;
}

CameraModel::CameraModel(const CameraOptions& options) : options_(options) {
  ThrowIfInvalid("camera", options.Validate());
  fx_ = options.focal_length_m / options.pixel_width_m;
  fy_ = options.focal_length_m / options.pixel_height_m;
  cu_ = options.principal_point_u_px.value_or(0.5 * options.image_width_px);
  cv_ = options.principal_point_v_px.value_or(0.5 * options.image_height_px);
  rotation_ = TiltRotation(options.tilt_rad) * RollRotation(options.roll_rad).transpose();
}

Eigen::Vector3d CameraModel::VehicleToCamera(const Eigen::Vector3d& p_vehicle) const {
  return rotation_ * (p_vehicle - centre());
}

std::optional<Eigen::Vector2d> CameraModel::Project(const Eigen::Vector3d& p_vehicle) const {
  const Eigen::Vector3d p = VehicleToCamera(p_vehicle);
  if (p.z() <= 1e-9) return std::nullopt;
  return Eigen::Vector2d(fx_ * p.x() / p.z() + cu_, fy_ * p.y() / p.z() + cv_);
}

Eigen::Matrix<double, 2, 3> CameraModel::ProjectJacobian(const Eigen::Vector3d& p_vehicle) const {
  const Eigen::Vector3d p = VehicleToCamera(p_vehicle);
  const double inv_z = 1.0 / p.z();
  Eigen::Matrix<double, 2, 3> d_uv_d_camera;
  d_uv_d_camera << fx_ * inv_z, 0.0, -fx_ * p.x() * inv_z * inv_z,  //
      0.0, fy_ * inv_z, -fy_ * p.y() * inv_z * inv_z;
  return d_uv_d_camera * rotation_;
}

Eigen::Vector3d CameraModel::Ray(const Eigen::Vector2d& uv) const {
  const Eigen::Vector3d q((uv.x() - cu_) / fx_, (uv.y() - cv_) / fy_, 1.0);
  return rotation_.transpose() * q;
}

std::optional<Eigen::Vector2d> CameraModel::ImageToPlane(const Eigen::Vector2d& uv,
                                                         double plane_height_m) const {
  const Eigen::Vector3d d = Ray(uv);
  const double drop = plane_height_m - options_.height_m;  // < 0 below the camera
  if (d.z() * drop <= 0.0) return std::nullopt;            // ray never reaches the plane
  const double s = drop / d.z();
  return Eigen::Vector2d(s * d.x(), s * d.y());
}

Eigen::Matrix2d CameraModel::ImageToPlaneJacobian(const Eigen::Vector2d& uv,
                                                  double plane_height_m) const {
  // x = Δz·d_x/d_z, y = Δz·d_y/d_z with d = Rᵀ q(u, v); quotient rule.
  const Eigen::Vector3d d = Ray(uv);
  const double drop = plane_height_m - options_.height_m;
  const Eigen::Vector3d dd_du = rotation_.row(0).transpose() / fx_;
  const Eigen::Vector3d dd_dv = rotation_.row(1).transpose() / fy_;
  const double inv_z2 = 1.0 / (d.z() * d.z());
  Eigen::Matrix2d j;
  j(0, 0) = drop * (dd_du.x() * d.z() - d.x() * dd_du.z()) * inv_z2;
  j(0, 1) = drop * (dd_dv.x() * d.z() - d.x() * dd_dv.z()) * inv_z2;
  j(1, 0) = drop * (dd_du.y() * d.z() - d.y() * dd_du.z()) * inv_z2;
  j(1, 1) = drop * (dd_dv.y() * d.z() - d.y() * dd_dv.z()) * inv_z2;
  return j;
}

Eigen::Matrix3d CameraModel::PlaneToImageHomography(double plane_height_m) const {
  Eigen::Matrix3d k;
  k << fx_, 0.0, cu_, 0.0, fy_, cv_, 0.0, 0.0, 1.0;
  Eigen::Matrix3d m;
  m.col(0) = rotation_.col(0);
  m.col(1) = rotation_.col(1);
  m.col(2) = rotation_.col(2) * plane_height_m - rotation_ * centre();
  return k * m;
}

bool CameraModel::InImage(const Eigen::Vector2d& uv, double margin_px) const {
  return uv.x() >= -margin_px && uv.y() >= -margin_px &&
         uv.x() <= options_.image_width_px + margin_px &&
         uv.y() <= options_.image_height_px + margin_px;
}

double CameraModel::HorizonV() const {
  // Rays with zero vertical component: the camera-frame direction (0, y, 1)
  // satisfies Rᵀ(·)·ẑ = 0 at the principal column (roll ignored here).
  const Eigen::Vector3d up_in_camera = rotation_.col(2);  // vehicle z in camera axes
  if (std::abs(up_in_camera.y()) < 1e-12) return -1e9;
  const double y_over_z = -up_in_camera.z() / up_in_camera.y();
  return fy_ * y_over_z + cv_;
}

}  // namespace plantscale::geometry
