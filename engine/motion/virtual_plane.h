#pragma once
// The virtual image plane (Sanchiz & Pla 1999, §2, eq. 1): the image plane a
// camera pointing straight down would have. Motion on the ground is a 2-D
// rigid motion there, and features at one depth move together.
//
// The engine carries virtual-plane points scaled by z_vc / f (eq. 8), i.e.
// metres on the feature plane in the vehicle frame; ImageToFeaturePlane does
// that in one step through the CameraModel (which also knows roll and the
// principal point). VirtualImagePoint is eq. 1 itself, kept for the tests
// that tie the two together.

#include <Eigen/Core>
#include <optional>

#include "engine/geometry/camera_model.h"

namespace plantscale::motion {

// Eq. 1: camera-frame image point (x_c right, y_c down, metres on the
// sensor, z_c = f) of a camera whose optical axis is `off_vertical_rad` from
// the vertical (90° − tilt below the horizontal), transferred to the virtual
// image plane (x_vc, y_vc), z_vc = f. Nullopt when the ray does not reach it.
std::optional<Eigen::Vector2d> VirtualImagePoint(const Eigen::Vector2d& xy_c, double focal_length_m,
                                                 double off_vertical_rad);

// A pixel (u, v) on the horizontal plane z = plane_height_m, vehicle frame,
// metres: the virtual image point scaled by (camera height − plane height) / f.
std::optional<Eigen::Vector2d> ImageToFeaturePlane(const geometry::CameraModel& camera,
                                                   const Eigen::Vector2d& uv, double plane_height_m);

}  // namespace plantscale::motion
