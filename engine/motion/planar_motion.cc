#include "engine/motion/planar_motion.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "engine/common/check.h"

namespace plantscale::motion {

Eigen::Matrix2d PlanarMotion::R() const { return Eigen::Rotation2Dd(psi_rad).toRotationMatrix(); }

Eigen::Vector2d PlanarMotion::ApplyInverse(const Eigen::Vector2d& p) const {
  return R().transpose() * (p - t_m);
}

PlanarMotion PlanarMotion::Inverse() const {
  return {-psi_rad, -(R().transpose() * t_m)};
}

PlanarMotion PlanarMotion::After(const PlanarMotion& first) const {
  return {WrapAngle(psi_rad + first.psi_rad), R() * first.t_m + t_m};
}

Eigen::Vector2d VehiclePose2::ToWorld(const Eigen::Vector2d& p) const {
  return Eigen::Rotation2Dd(heading_rad) * p + position_m;
}

Eigen::Vector2d VehiclePose2::FromWorld(const Eigen::Vector2d& world) const {
  return Eigen::Rotation2Dd(-heading_rad) * (world - position_m);
}

VehiclePose2 Compose(const VehiclePose2& previous, const PlanarMotion& frame_to_frame) {
  VehiclePose2 next;
  next.heading_rad = WrapAngle(previous.heading_rad - frame_to_frame.psi_rad);
  next.position_m = previous.position_m - Eigen::Rotation2Dd(next.heading_rad) * frame_to_frame.t_m;
  return next;
}

double WrapAngle(double a_rad) {
  const double wrapped = std::remainder(a_rad, 2.0 * M_PI);
  return wrapped <= -M_PI ? wrapped + 2.0 * M_PI : wrapped;
}

PlanarMotion FitRigidMotion(std::span<const Eigen::Vector2d> from,
                            std::span<const Eigen::Vector2d> to,
                            std::span<const double> weights) {
  PLANTSCALE_CHECK(from.size() == to.size() && !from.empty(), "need matched, non-empty sets");
  PLANTSCALE_CHECK(weights.empty() || weights.size() == from.size(), "one weight per pair");
  const auto w = [&](size_t i) { return weights.empty() ? 1.0 : weights[i]; };
  double total = 0.0;
  Eigen::Vector2d mean_from = Eigen::Vector2d::Zero(), mean_to = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < from.size(); ++i) {
    total += w(i);
    mean_from += w(i) * from[i];
    mean_to += w(i) * to[i];
  }
  PLANTSCALE_CHECK(total > 0.0, "weights must not all be zero");
  mean_from /= total;
  mean_to /= total;
  // Umeyama's covariance; in 2-D the optimal rotation is the angle of
  // (Σ dot, Σ cross) of the centred pairs, a true rotation by construction.
  double dot = 0.0, cross = 0.0;
  for (size_t i = 0; i < from.size(); ++i) {
    const Eigen::Vector2d a = from[i] - mean_from, b = to[i] - mean_to;
    dot += w(i) * a.dot(b);
    cross += w(i) * (a.x() * b.y() - a.y() * b.x());
  }
  PlanarMotion m;
  m.psi_rad = (dot == 0.0 && cross == 0.0) ? 0.0 : std::atan2(cross, dot);
  m.t_m = mean_to - m.R() * mean_from;
  return m;
}

MatchTriangulation Triangulate(const PlanarMotion& motion, const Eigen::Vector2d& previous,
                               const Eigen::Vector2d& current) {
  // Eq. 9: the match's own translation at the motion's rotation.
  const Eigen::Vector2d t_obs = current - motion.R() * previous;
  MatchTriangulation out;
  const double norm = t_obs.norm(), reference = motion.t_m.norm();
  // Eq. 10 in plane units: z_obs / z = |t| / |t_obs|.
  out.depth_ratio = norm > 0.0 ? reference / norm : std::numeric_limits<double>::infinity();
  if (norm > 0.0 && reference > 0.0) {
    const double c = t_obs.x() * motion.t_m.y() - t_obs.y() * motion.t_m.x();
    out.direction_error_rad = std::abs(std::atan2(c, t_obs.dot(motion.t_m)));
  }
  return out;
}

}  // namespace plantscale::motion
