#include "engine/motion/feature_filter.h"

#include <gtest/gtest.h>

namespace plantscale::motion {
namespace {

TEST(FeatureFilter, PredictionIsTheChangeOfCoordinatesOfEquationTwo) {
  const Eigen::Matrix2d p0 = 0.01 * Eigen::Matrix2d::Identity();
  FeatureFilter f({0.1, 0.6}, p0);
  const PlanarMotion m{0.05, {0.01, -0.25}};
  const Eigen::Matrix2d r1 = 1e-4 * Eigen::Matrix2d::Identity();
  f.Predict(m, r1);
  EXPECT_LT((f.position_m() - m.Apply({0.1, 0.6})).norm(), 1e-12);
  // Isotropic P is unchanged by the rotation; R₁ adds (eq. 15).
  EXPECT_LT((f.covariance() - (p0 + r1)).norm(), 1e-12);
}

TEST(FeatureFilter, UpdateWeighsPredictionAndObservationByTheirCovariances) {
  const Eigen::Matrix2d p = 4e-4 * Eigen::Matrix2d::Identity();
  FeatureFilter f({0.0, 0.5}, p);
  f.Update({0.02, 0.5}, p);  // equal uncertainty: halfway, covariance halved
  EXPECT_NEAR(f.position_m().x(), 0.01, 1e-12);
  EXPECT_NEAR(f.covariance()(0, 0), 2e-4, 1e-15);
  f.Update({0.01, 0.5}, 1e6 * p);  // a useless observation barely moves it
  EXPECT_NEAR(f.position_m().x(), 0.01, 1e-9);
}

TEST(FeatureFilter, CoastingGrowsTheUncertaintyUntilTheFeatureIsSeenAgain) {
  const Eigen::Matrix2d s = 1e-6 * Eigen::Matrix2d::Identity();
  FeatureFilter f({0.0, 0.7}, s);
  const PlanarMotion m{0.0, {0.0, -0.1}};
  for (int k = 0; k < 3; ++k) f.Predict(m, s);  // three missed detections
  EXPECT_NEAR(f.position_m().y(), 0.4, 1e-12);
  EXPECT_NEAR(f.covariance()(1, 1), 4e-6, 1e-15);
  f.Update({0.0, 0.401}, s);
  EXPECT_NEAR(f.position_m().y(), 0.4 + 0.001 * 0.8, 1e-12);  // K = 4/5
}

}  // namespace
}  // namespace plantscale::motion
