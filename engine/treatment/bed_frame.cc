#include "engine/treatment/bed_frame.h"

#include <cmath>

namespace plantscale::treatment {

BedPose BedPoseFromGrid(int64_t utime, const geometry::GridState& grid, double forward_distance_m,
                        double speed_m_s) {
  BedPose p;
  p.utime = utime;
  p.offset_m = grid.offset_m;
  p.bearing_rad = grid.bearing_rad;
  p.distance_m = forward_distance_m;
  p.speed_m_s = speed_m_s;
  return p;
}

Eigen::Vector2d VehicleToBed(const BedPose& pose, const Eigen::Vector2d& v) {
  const double c = std::cos(pose.bearing_rad), s = std::sin(pose.bearing_rad);
  const double dx = v.x() - pose.offset_m;
  const double dy = v.y();
  // Rᵀ with R = [c s; −s c]: g = [c −s; s c] (v − t).
  return {c * dx - s * dy, pose.distance_m + s * dx + c * dy};
}

Quad VehicleToBed(const BedPose& pose, const Quad& v) {
  Quad bed;
  for (size_t i = 0; i < 4; ++i) bed[i] = VehicleToBed(pose, v[i]);
  return bed;
}

Eigen::Vector2d BedToVehicle(const BedPose& pose, const Eigen::Vector2d& b) {
  const double c = std::cos(pose.bearing_rad), s = std::sin(pose.bearing_rad);
  const double gx = b.x();
  const double gy = b.y() - pose.distance_m;
  return {c * gx + s * gy + pose.offset_m, -s * gx + c * gy};
}

bool InsideQuad(const Quad& q, const Eigen::Vector2d& p) {
  bool any_pos = false, any_neg = false;
  for (size_t i = 0; i < 4; ++i) {
    const Eigen::Vector2d& a = q[i];
    const Eigen::Vector2d& b = q[(i + 1) % 4];
    const double c = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
    any_pos |= c > 0.0;
    any_neg |= c < 0.0;
  }
  return !(any_pos && any_neg);
}

std::optional<Quad> FootprintOnPlane(const geometry::CameraModel& camera,
                                     const Eigen::Vector2d& centroid_px, double u0, double v0,
                                     double u1, double v1, double scale,
                                     std::optional<double> plane_height_m) {
  const double plane = plane_height_m.value_or(camera.options().virtual_plane_height_m);
  const Eigen::Vector2d corners[4] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
  Quad q;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d uv = centroid_px + scale * (corners[i] - centroid_px);
    const std::optional<Eigen::Vector2d> g = camera.ImageToPlane(uv, plane);
    if (!g) return std::nullopt;
    q[static_cast<size_t>(i)] = *g;
  }
  return q;
}

}  // namespace plantscale::treatment
