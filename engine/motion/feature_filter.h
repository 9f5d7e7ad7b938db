#pragma once
// The per-feature Kalman filter of Sanchiz & Pla §4 (eqs. 12–23): the state
// is the feature's position on the virtual plane (here in metres, eq. 8),
// the transition is the frame-to-frame rotation (eq. 20), the input the
// translation (eq. 21), and the measurement the observed position (C = I).
// A feature that is not observed is only predicted (a change of
// coordinates), so it coasts through missed detections.

#include <Eigen/Core>

#include "engine/motion/planar_motion.h"

namespace plantscale::motion {

class FeatureFilter {
 public:
  // x₀|₀ = observation, P₀ = p0 (eq. 23).
  FeatureFilter(const Eigen::Vector2d& observation_m, const Eigen::Matrix2d& p0);

  // Eqs. 14–15 with Φ = r, Γu = t: x ← r x + t, P ← r P rᵀ + R₁.
  void Predict(const PlanarMotion& motion, const Eigen::Matrix2d& r1);
  // Eqs. 16–18 with C = I.
  void Update(const Eigen::Vector2d& observation_m, const Eigen::Matrix2d& r2);

  const Eigen::Vector2d& position_m() const { return x_; }
  const Eigen::Matrix2d& covariance() const { return p_; }

 private:
  Eigen::Vector2d x_;
  Eigen::Matrix2d p_;
};

}  // namespace plantscale::motion
