#include "engine/motion/feature_filter.h"

#include <Eigen/LU>

namespace plantscale::motion {

FeatureFilter::FeatureFilter(const Eigen::Vector2d& observation_m, const Eigen::Matrix2d& p0)
    : x_(observation_m), p_(p0) {}

void FeatureFilter::Predict(const PlanarMotion& motion, const Eigen::Matrix2d& r1) {
  const Eigen::Matrix2d phi = motion.R();  // eq. 20
  x_ = phi * x_ + motion.t_m;              // eq. 14 (22)
  p_ = phi * p_ * phi.transpose() + r1;    // eq. 15
}

void FeatureFilter::Update(const Eigen::Vector2d& observation_m, const Eigen::Matrix2d& r2) {
  const Eigen::Matrix2d k = p_ * (p_ + r2).inverse();                     // eq. 16
  x_ += k * (observation_m - x_);                                         // eq. 17
  p_ = (Eigen::Matrix2d::Identity() - k) * p_;                            // eq. 18
  p_ = 0.5 * (p_ + p_.transpose());
}

}  // namespace plantscale::motion
