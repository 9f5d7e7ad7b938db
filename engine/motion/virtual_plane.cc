#include "engine/motion/virtual_plane.h"

#include <cmath>

namespace plantscale::motion {

std::optional<Eigen::Vector2d> VirtualImagePoint(const Eigen::Vector2d& xy_c, double focal_length_m,
                                                 double off_vertical_rad) {
  // Eq. 1: rotate by φ about x_c, then project back onto z = f.
  const double f = focal_length_m, s = std::sin(off_vertical_rad), c = std::cos(off_vertical_rad);
  const double depth = xy_c.y() * s + f * c;  // z'_vc
  if (depth <= 0.0) return std::nullopt;
  return Eigen::Vector2d(f * xy_c.x() / depth, f * (xy_c.y() * c - f * s) / depth);
}

std::optional<Eigen::Vector2d> ImageToFeaturePlane(const geometry::CameraModel& camera,
                                                   const Eigen::Vector2d& uv, double plane_height_m) {
  return camera.ImageToPlane(uv, plane_height_m);
}

}  // namespace plantscale::motion
