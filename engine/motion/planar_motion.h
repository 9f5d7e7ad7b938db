#pragma once
// Planar motion between consecutive frames (Sanchiz & Pla 1999, §2).
//
// Points are carried on the feature plane in metres, vehicle frame (x right,
// y forward): a point of the paper's virtual image plane scaled by z_vc / f
// (eq. 8), so eq. 2 loses its f / z_vc factor:
//   p_k = r_{k,k-1} p_{k-1} + t_{k,k-1}                       (eq. 2)
// The frame-to-frame motion is the motion of the scene, opposed to the
// vehicle's; the vehicle's absolute pose follows by eq. 4.

#include <Eigen/Core>
#include <span>

namespace plantscale::motion {

// (r, t) of eq. 7: rotation ψ (CCW, radians) and translation (metres).
struct PlanarMotion {
  double psi_rad = 0.0;
  Eigen::Vector2d t_m{0.0, 0.0};

  Eigen::Matrix2d R() const;
  Eigen::Vector2d Apply(const Eigen::Vector2d& p) const { return R() * p + t_m; }  // eq. 2
  Eigen::Vector2d ApplyInverse(const Eigen::Vector2d& p) const;                     // eq. 3
  PlanarMotion Inverse() const;
  // The motion that applies `first`, then this.
  PlanarMotion After(const PlanarMotion& first) const;
};

// Absolute pose of the vehicle in the frame of the first image (eq. 4):
// a point p seen at frame k lies at R_k p + T_k in the world.
struct VehiclePose2 {
  double heading_rad = 0.0;  // angle of R_k
  Eigen::Vector2d position_m{0.0, 0.0};

  Eigen::Vector2d ToWorld(const Eigen::Vector2d& p) const;
  Eigen::Vector2d FromWorld(const Eigen::Vector2d& world) const;
};

// Eq. 4: R_k = R_{k-1} r⁻¹, T_k = T_{k-1} − R_k t.
VehiclePose2 Compose(const VehiclePose2& previous, const PlanarMotion& frame_to_frame);

// Wraps an angle to (−π, π].
double WrapAngle(double a_rad);

// Least-squares rigid motion taking `from` onto `to` (Umeyama 1991, in 2-D,
// without scale: always a true rotation). Weights default to 1. Needs at
// least one pair (one pair gives a pure translation with ψ = 0).
PlanarMotion FitRigidMotion(std::span<const Eigen::Vector2d> from,
                            std::span<const Eigen::Vector2d> to,
                            std::span<const double> weights = {});

// Triangulation of one match against a motion (§3.4 step 4, eqs. 9–11):
// the depth ratio z_vc(obs) / z_vc that makes the match's translation as
// long as `motion`'s, and the angle between the match's translation and
// `motion`'s. A match without translation has an infinite ratio.
struct MatchTriangulation {
  double depth_ratio = 1.0;
  double direction_error_rad = 0.0;
};
MatchTriangulation Triangulate(const PlanarMotion& motion, const Eigen::Vector2d& previous,
                               const Eigen::Vector2d& current);

}  // namespace plantscale::motion
