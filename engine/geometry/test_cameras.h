#pragma once
// Cameras shared by the geometry and simulator tests and the benchmarks.

#include <numbers>

#include "engine/geometry/camera_model.h"

namespace plantscale::geometry::testing {

inline double Degrees(double deg) { return deg * std::numbers::pi / 180.0; }

// An oblique camera like the thesis vehicle's.
inline CameraOptions ObliqueCamera() {
  CameraOptions o;
  o.height_m = 1.6;
  o.tilt_rad = Degrees(40.0);
  o.focal_length_m = 0.0048;
  o.pixel_width_m = 8.6e-6;
  o.pixel_height_m = 8.3e-6;
  o.image_width_px = 640;
  o.image_height_px = 480;
  o.principal_point_u_px = 322.5;
  o.principal_point_v_px = 236.0;
  return o;
}

// The thesis vehicle camera as shipped in config/cameras/thesis.yaml.
inline CameraOptions ThesisCamera() {
  CameraOptions o;
  o.height_m = 1.5;
  o.tilt_rad = Degrees(45.0);
  o.focal_length_m = 0.0048;
  o.pixel_width_m = 8.6e-6;
  o.pixel_height_m = 8.3e-6;
  o.image_width_px = 640;
  o.image_height_px = 480;
  return o;
}

// A rolled, pitched camera with a virtual plane, to exercise every term.
inline CameraOptions DisturbedCamera() {
  CameraOptions o = ObliqueCamera();
  o.roll_rad = Degrees(3.0);
  o.tilt_rad = Degrees(47.0);
  o.virtual_plane_height_m = 0.12;
  return o;
}

}  // namespace plantscale::geometry::testing
