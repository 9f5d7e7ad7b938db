#include "engine/pipeline/motion_fusion.h"

#include <gtest/gtest.h>

namespace plantscale::pipeline {
namespace {

TEST(MotionFusion, WheelsAloneWithoutACameraEstimate) {
  const PlanarSpeed wheels{0.7, 0.01, 0.015, 0.02};
  const FusedSpeed f = Fuse(wheels, nullptr, 13.8);
  EXPECT_EQ(f.source, FusedSource::kWheels);
  EXPECT_DOUBLE_EQ(f.speed.speed_m_s, 0.7);
  EXPECT_DOUBLE_EQ(f.chi2, 0.0);
}

TEST(MotionFusion, AgreeingSourcesArePrecisionWeighted) {
  // σ 0.01 and 0.02: weights 4 : 1.
  const PlanarSpeed wheels{0.70, 0.00, 0.01, 0.02};
  const PlanarSpeed camera{0.72, 0.01, 0.02, 0.02};
  const FusedSpeed f = Fuse(wheels, &camera, 13.8);
  EXPECT_EQ(f.source, FusedSource::kFused);
  EXPECT_NEAR(f.speed.speed_m_s, (4.0 * 0.70 + 0.72) / 5.0, 1e-12);
  EXPECT_NEAR(f.speed.speed_sd_m_s, 1.0 / std::sqrt(1.0 / 1e-4 + 1.0 / 4e-4), 1e-12);
  EXPECT_NEAR(f.speed.yaw_rate_rad_s, 0.005, 1e-12);
  EXPECT_NEAR(f.chi2, 0.0004 / 0.0005 + 0.0001 / 0.0008, 1e-9);
}

TEST(MotionFusion, SpinningWheelsGiveWayToTheCamera) {
  const PlanarSpeed wheels{0.91, 0.0, 0.02, 0.02};  // 30 % spin
  const PlanarSpeed camera{0.70, 0.0, 0.02, 0.02};
  const FusedSpeed f = Fuse(wheels, &camera, 13.8);
  EXPECT_EQ(f.source, FusedSource::kCamera);
  EXPECT_DOUBLE_EQ(f.speed.speed_m_s, 0.70);
}

TEST(MotionFusion, AStalledEncoderShowsAsATurnTheCameraDoesNotSee) {
  MotionFusionOptions o;
  const PlanarSpeed wheels = WheelSpeed(0.0, 0.7, 1.0, 1.5, o);  // left reads 0
  EXPECT_NEAR(wheels.yaw_rate_rad_s, 0.7 / 1.5, 1e-12);
  const PlanarSpeed camera{0.70, 0.0, 0.02, 0.01};
  EXPECT_EQ(Fuse(wheels, &camera, o.gate_chi2).source, FusedSource::kCamera);
}

TEST(MotionFusion, WheelSpeedsRoundTrip) {
  MotionFusionOptions o;
  const PlanarSpeed s = WheelSpeed(0.68, 0.73, 1.04, 1.5, o);
  double left = 0.0, right = 0.0;
  ToWheels(s, 1.04, 1.5, left, right);
  EXPECT_NEAR(left, 0.68, 1e-12);
  EXPECT_NEAR(right, 0.73, 1e-12);
  // 3 % of each wheel's ground speed.
  EXPECT_NEAR(s.speed_sd_m_s, 0.5 * std::hypot(0.03 * 0.68 * 1.04, 0.03 * 0.73 * 1.04), 1e-12);
}

TEST(MotionFusion, OneWheelSigmaCarriesSpeedAndTurnRate) {
  const PlanarSpeed s{0.7, 0.0, 0.03, 0.04};
  // σ_wheel = √(0.03² + (0.04·0.75)²) = 0.0424; over 0.7 m/s.
  EXPECT_NEAR(WheelSdFraction(s, 1.5), std::hypot(0.03, 0.03) / 0.7, 1e-12);
  EXPECT_NEAR(WheelSdFraction({0.0, 0.0, 0.03, 0.0}, 1.5), 0.3, 1e-12);  // speed floor
}

TEST(MotionFusion, OptionsExplainWhatIsWrong) {
  MotionFusionOptions o;
  o.gate_chi2 = 0.0;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].key, "gate_chi2");
}

}  // namespace
}  // namespace plantscale::pipeline
