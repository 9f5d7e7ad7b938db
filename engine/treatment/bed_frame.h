#pragma once
// The bed frame: the field frame the treatment map lives in, as the grid
// tracker defines it (docs/design.md §3: x across the rows with the central row at
// x = 0, y along the rows), anchored at the tracker's initialisation. A
// vehicle-frame point v maps to grid coordinates g by inverting eq. A.1,
//
//   g = R(Ψ)ᵀ (v − (t_x, 0)),   R(Ψ) = [cos Ψ  sin Ψ; −sin Ψ  cos Ψ],
//
// and to the bed as (g_x, s + g_y), with s the distance driven along the rows
// since initialisation (GridTracker::forward_distance_m: l̄ per line passed
// minus the change of Y), so a plant at line m keeps the same bed position
// however the tracker renumbers its lines (eq. 4.6).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>

#include "engine/geometry/camera_model.h"
#include "engine/geometry/grid_model.h"

namespace plantscale::treatment {

struct BedPose {
  int64_t utime = 0;
  double offset_m = 0.0;    // t_x
  double bearing_rad = 0.0; // Ψ
  double distance_m = 0.0;  // s: the vehicle origin's bed y
  double speed_m_s = 0.0;   // forward, from odometry
};

BedPose BedPoseFromGrid(int64_t utime, const geometry::GridState& grid, double forward_distance_m,
                        double speed_m_s);

Eigen::Vector2d VehicleToBed(const BedPose& pose, const Eigen::Vector2d& vehicle_m);
Eigen::Vector2d BedToVehicle(const BedPose& pose, const Eigen::Vector2d& bed_m);

using Quad = std::array<Eigen::Vector2d, 4>;
// The quad's corners, vehicle frame to bed frame.
Quad VehicleToBed(const BedPose& pose, const Quad& vehicle_m);

// p inside a convex quad of either winding (the boundary counts).
bool InsideQuad(const Quad& q, const Eigen::Vector2d& p);

// A blob's footprint on the virtual ground plane (vehicle frame): its image
// bounding box scaled by `scale` about the centroid, corners projected
// (thesis §8.2: "the bounding box of each feature is projected from the image
// to a quadrilateral area of the map"; scale 1 is the thesis's). nullopt when
// a corner's ray misses the plane. The plane is the camera's virtual plane,
// or `plane_height_m` (where the plant's centroid was located).
std::optional<Quad> FootprintOnPlane(const geometry::CameraModel& camera,
                                     const Eigen::Vector2d& centroid_px, double u0, double v0,
                                     double u1, double v1, double scale,
                                     std::optional<double> plane_height_m = std::nullopt);

}  // namespace plantscale::treatment
