#include "engine/pipeline/motion_fusion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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

TEST(VisualScale, LearnsTheCameraScaleOnceItHasDrivenEnough) {
  MotionFusionOptions o;  // memory 20 m, applied after 3 m
  VisualScale scale(o);
  // The camera reads 4 % short: 0.672 m/s against the wheels' 0.7, 50 Hz.
  for (int i = 0; i < 100; ++i) scale.Add(0.7, 0.672, 0.02);  // 1.34 m of camera travel
  EXPECT_DOUBLE_EQ(scale.ratio(), 1.0);
  for (int i = 0; i < 200; ++i) scale.Add(0.7, 0.672, 0.02);  // 4.0 m in all
  EXPECT_NEAR(scale.ratio(), 0.7 / 0.672, 1e-9);
  EXPECT_NEAR(Scaled({0.672, 0.05, 0.03, 0.02}, scale.ratio()).speed_m_s, 0.7, 1e-9);
  EXPECT_NEAR(Scaled({0.672, 0.05, 0.03, 0.02}, scale.ratio()).yaw_rate_rad_s, 0.05, 1e-12);
}

TEST(VisualScale, ForgetsOldAgreementOverItsMemory) {
  MotionFusionOptions o;
  VisualScale scale(o);
  for (int i = 0; i < 1000; ++i) scale.Add(0.7, 0.672, 0.02);  // 14 m at −4 %
  // Then 60 m (three memories) at +2 %: the old share is e^−3 ≈ 5 % of the
  // sums, so the ratio is within 0.3 % of the new one.
  for (int i = 0; i < 4286; ++i) scale.Add(0.7, 0.714, 0.02);
  EXPECT_NEAR(scale.ratio(), 0.7 / 0.714, 0.003);
  EXPECT_GT(scale.ratio(), 0.7 / 0.714);  // what is left of the old pulls it up
}

TEST(VisualScale, StaysWithinItsBoundsAndRefusesNonsense) {
  MotionFusionOptions o;
  VisualScale scale(o);
  for (int i = 0; i < 1000; ++i) scale.Add(0.7, 0.35, 0.02);  // half: beyond ±20 %
  EXPECT_DOUBLE_EQ(scale.ratio(), 1.2);
  VisualScale other(o);
  other.Add(std::nan(""), 0.7, 0.02);
  other.Add(0.7, 0.7, -1.0);
  for (int i = 0; i < 1000; ++i) other.Add(0.7, 0.7, 0.02);
  EXPECT_NEAR(other.ratio(), 1.0, 1e-12);
}

// Frame-to-frame camera noise of σ 0.03 m/s about the true 0.70 m/s (a fixed
// pseudo-random sequence), wheels of σ 0.02 m/s.
double CameraNoise(int i) { return 0.03 * std::sin(12.9898 * i + 4.1) * 1.41; }

TEST(PersistentDisagreement, AScaleErrorEachFrameWithinTheGateStandsOutOverTheWindow) {
  MotionFusionOptions o;  // 12 frames, 4σ
  PersistentDisagreement window(o);
  for (int i = 0; i < 11; ++i) {
    // Wheels 20 % short (0.56) against a camera reading 0.64 ± noise: each
    // frame's χ² is (0.08 / 0.036)² ≈ 5, within the per-sample gate of 13.8.
    const PlanarSpeed wheels{0.56, 0.0, 0.02, 0.02};
    const PlanarSpeed camera{0.64 + 0.3 * CameraNoise(i), 0.0, 0.03, 0.02};
    EXPECT_EQ(Fuse(wheels, &camera, o.gate_chi2).source, FusedSource::kFused) << i;
    window.Add(1000 * i, wheels, camera);
    EXPECT_FALSE(window.wheels_off()) << "not before the window is full, frame " << i;
  }
  window.Add(11000, {0.56, 0.0, 0.02, 0.02}, {0.64, 0.0, 0.03, 0.02});
  // Mean difference −0.08 over 12 frames of σ √(0.02² + 0.03²) = 0.036:
  // z = −0.08 · 12 / (0.036 · √12) ≈ −7.7.
  EXPECT_NEAR(window.z(), -0.08 * 12.0 / std::sqrt(12.0 * 13e-4), 0.3);
  EXPECT_TRUE(window.wheels_off());
}

TEST(PersistentDisagreement, SoundWheelsAndANoisyCameraAreNotCondemned) {
  MotionFusionOptions o;
  PersistentDisagreement window(o);
  double largest = 0.0;
  for (int i = 0; i < 500; ++i) {
    window.Add(1000 * i, {0.70, 0.0, 0.02, 0.02}, {0.70 + CameraNoise(i), 0.0, 0.03, 0.02});
    largest = std::max(largest, std::abs(window.z()));
    EXPECT_FALSE(window.wheels_off()) << i;
  }
  EXPECT_GT(largest, 0.3);  // the statistic moves with the noise
}

TEST(PersistentDisagreement, OneEstimateCountsOnceAndTheWindowForgets) {
  MotionFusionOptions o;
  o.persistence_frames = 4;
  PersistentDisagreement window(o);
  const PlanarSpeed wheels{0.56, 0.0, 0.02, 0.02}, camera{0.70, 0.0, 0.03, 0.02};
  // Five odometry samples against the same camera estimate: one frame.
  for (int i = 0; i < 5; ++i) window.Add(7, wheels, camera);
  EXPECT_DOUBLE_EQ(window.z(), 0.0);
  for (int i = 1; i < 4; ++i) window.Add(7 + i, wheels, camera);
  EXPECT_NEAR(window.z(), -0.14 * 4.0 / std::sqrt(4.0 * 13e-4), 1e-9);
  EXPECT_TRUE(window.wheels_off());
  // The wheels at the camera's speed, with the σ of the window's mean added.
  const PlanarSpeed corrected = window.Corrected(wheels);
  EXPECT_NEAR(corrected.speed_m_s, 0.70, 1e-12);
  EXPECT_NEAR(corrected.speed_sd_m_s, std::sqrt(4e-4 + 4.0 * 13e-4 / 16.0), 1e-12);
  EXPECT_DOUBLE_EQ(corrected.yaw_rate_rad_s, wheels.yaw_rate_rad_s);
  // The wheels back in agreement: after four frames the fault is forgotten.
  for (int i = 4; i < 8; ++i) window.Add(7 + i, camera, camera);
  EXPECT_NEAR(window.z(), 0.0, 1e-12);
  EXPECT_FALSE(window.wheels_off());
}

TEST(MotionFusion, OptionsExplainWhatIsWrong) {
  MotionFusionOptions o;
  o.gate_chi2 = 0.0;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].key, "gate_chi2");
  MotionFusionOptions bound;
  bound.scale_bound = 1.0;
  ASSERT_EQ(bound.Validate().size(), 1U);
  EXPECT_EQ(bound.Validate()[0].key, "scale_bound");
  MotionFusionOptions window;
  window.persistence_frames = PersistentDisagreement::kMaxFrames + 1;
  ASSERT_EQ(window.Validate().size(), 1U);
  EXPECT_EQ(window.Validate()[0].key, "persistence_frames");
}

}  // namespace
}  // namespace plantscale::pipeline
