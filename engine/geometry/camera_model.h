#pragma once
// Southall's camera model (thesis §2.2.1, eqs. 2.3–2.6; appendix A.1),
// written without its small-angle approximations and with the camera
// height rather than the along-axis distance t_z as the parameter.
//
// Frames (docs/design.md §3):
//   vehicle: origin on the ground directly below the optical centre,
//            x right, y forward, z up; metres.
//   camera:  optical centre, x right, y down the image, z along the optical axis.
//   image:   pixels, origin at the top-left corner of the top-left pixel,
//            u right, v down; the centre of the first pixel is (0.5, 0.5).
//
// The thesis measures φ from the vertical and t_z along the optical axis to
// the ground; here tilt is the angle of the optical axis *below the
// horizontal* (Sanchiz & Pla's φ: 90° looks straight down), so
//   φ_thesis = 90° − tilt,   t_z = height / sin(tilt).
// A roll about the vehicle's forward axis models bumps (the thesis assumes
// none); tilt changes model pitch.

#include <Eigen/Core>
#include <array>
#include <optional>

#include "engine/common/options.h"

namespace plantscale::geometry {

struct CameraOptions {
  double height_m = 1.2;           // optical centre above the soil
  double tilt_rad = 0.8727;        // optical axis below the horizontal, (0, π/2]
  double roll_rad = 0.0;           // about the vehicle's forward axis (bumps)
  double focal_length_m = 0.006;   // f
  double pixel_width_m = 9.0e-6;   // dx
  double pixel_height_m = 9.0e-6;  // dy
  int image_width_px = 640;
  int image_height_px = 480;
  std::optional<double> principal_point_u_px;  // C_x; image centre when unset
  std::optional<double> principal_point_v_px;  // C_y; image centre when unset
  double virtual_plane_height_m = 0.0;  // plant height for the virtual ground plane (§2.3.8)

  OptionErrors Validate() const;
};

class CameraModel {
 public:
  // Throws InvalidOptionsError when the options are invalid.
  explicit CameraModel(const CameraOptions& options);

  const CameraOptions& options() const { return options_; }
  int width() const { return options_.image_width_px; }
  int height() const { return options_.image_height_px; }
  double fx() const { return fx_; }  // f / dx, pixels
  double fy() const { return fy_; }  // f / dy, pixels
  Eigen::Vector2d principal_point() const { return {cu_, cv_}; }
  Eigen::Vector3d centre() const { return {0.0, 0.0, options_.height_m}; }
  // Rows are the camera axes expressed in the vehicle frame.
  const Eigen::Matrix3d& rotation() const { return rotation_; }

  Eigen::Vector3d VehicleToCamera(const Eigen::Vector3d& p_vehicle) const;
  // Pinhole projection; nullopt when the point is not in front of the camera.
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_vehicle) const;
  // d(u, v) / d(x, y, z) in the vehicle frame.
  Eigen::Matrix<double, 2, 3> ProjectJacobian(const Eigen::Vector3d& p_vehicle) const;

  // Unit-free ray direction (vehicle frame) through a pixel position.
  Eigen::Vector3d Ray(const Eigen::Vector2d& uv) const;
  // Intersection of the pixel's ray with the horizontal plane z = plane_height_m
  // (vehicle frame x, y); nullopt when the ray does not reach the plane.
  std::optional<Eigen::Vector2d> ImageToPlane(const Eigen::Vector2d& uv,
                                              double plane_height_m) const;
  // The same onto the virtual ground plane at plant height (§2.3.8).
  std::optional<Eigen::Vector2d> ImageToVirtualPlane(const Eigen::Vector2d& uv) const {
    return ImageToPlane(uv, options_.virtual_plane_height_m);
  }
  // d(x, y) / d(u, v) of ImageToPlane.
  Eigen::Matrix2d ImageToPlaneJacobian(const Eigen::Vector2d& uv, double plane_height_m) const;

  // Homography taking (x, y, 1) on the plane z = plane_height_m to (u, v, 1)·w.
  Eigen::Matrix3d PlaneToImageHomography(double plane_height_m) const;
  bool InImage(const Eigen::Vector2d& uv, double margin_px = 0.0) const;
  // Image v of the horizon (rays above it never reach the ground); may lie
  // outside the image.
  double HorizonV() const;

 private:
  CameraOptions options_;
  double fx_ = 0.0;
  double fy_ = 0.0;
  double cu_ = 0.0;
  double cv_ = 0.0;
  Eigen::Matrix3d rotation_;
};

}  // namespace plantscale::geometry
