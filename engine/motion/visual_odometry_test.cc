#include "engine/motion/visual_odometry.h"

#include <gtest/gtest.h>

#include "engine/motion/test_scenes.h"

namespace plantscale::motion {
namespace {

using testing::Observe;
using testing::SanchizPlaCamera;
using testing::ScatterPoints;

// 0.7 m/s at 12.5 frames/s with a slow left turn, over a scatter of ground
// features with 1 mm noise.
class VisualOdometryTest : public ::testing::Test {
 protected:
  VisualOdometryTest() : camera_(SanchizPlaCamera()), points_(ScatterPoints(6.0, 330.0, 3)) {
    options_.tracker.method = MotionMethod::kOurs;
    options_.tracker.fit_row_heading = false;
  }
  std::vector<Feature> Frame(int k) {
    VehiclePose2 pose;
    for (int i = 0; i < k; ++i) pose = Compose(pose, scene_);
    return Observe(points_, pose, camera_, 0.001, rng_);
  }
  static int64_t Utime(int k) { return 1000000 + k * 80000; }

  const double dt_ = 0.08, speed_ = 0.7, yaw_rate_ = 0.02;
  const PlanarMotion scene_{-yaw_rate_ * dt_, {0.0, -speed_ * dt_}};
  geometry::CameraModel camera_;
  std::vector<testing::ScenePoint> points_;
  VisualOdometryOptions options_;
  std::mt19937 rng_{5};
};

TEST_F(VisualOdometryTest, RecoversSpeedAndTurnRateAroundAWrongPrior) {
  VisualOdometry vo(camera_, options_);
  EXPECT_FALSE(vo.UpdateFeatures(Utime(0), Frame(0), speed_, 0.0).valid);
  for (int k = 1; k < 15; ++k) {
    // The wheels spin: the prior reads 20 % fast.
    const VisualMotion& m = vo.UpdateFeatures(Utime(k), Frame(k), 1.2 * speed_, 0.0);
    ASSERT_TRUE(m.valid) << "frame " << k << ": " << m.reason;
    EXPECT_NEAR(m.speed_m_s, speed_, 0.02) << "frame " << k;  // 1.6 mm over a frame
    EXPECT_NEAR(m.yaw_rate_rad_s, yaw_rate_, 0.03) << "frame " << k;
    EXPECT_GT(m.speed_sd_m_s, 0.0);
    EXPECT_GE(m.matches, options_.min_matches);
  }
}

TEST_F(VisualOdometryTest, AFrameWithoutFeaturesIsInvalid) {
  VisualOdometry vo(camera_, options_);
  vo.UpdateFeatures(Utime(0), Frame(0), speed_, 0.0);
  const VisualMotion& m = vo.UpdateFeatures(Utime(1), {}, speed_, 0.0);
  EXPECT_FALSE(m.valid);
  EXPECT_EQ(m.reason, "no features");
  EXPECT_TRUE(vo.UpdateFeatures(Utime(2), Frame(2), speed_, 0.0).valid) << vo.last().reason;
}

TEST_F(VisualOdometryTest, AFrameOfAllNewFeaturesIsInvalid) {
  VisualOdometry vo(camera_, options_);
  vo.UpdateFeatures(Utime(0), Frame(0), speed_, 0.0);
  // Somewhere else entirely: none of the tracks is in it.
  const std::vector<testing::ScenePoint> other = ScatterPoints(6.0, 330.0, 99);
  VehiclePose2 far;
  far.position_m = {0.0, 3.0};
  const VisualMotion& m =
      vo.UpdateFeatures(Utime(1), Observe(other, far, camera_, 0.001, rng_), speed_, 0.0);
  EXPECT_FALSE(m.valid);
}

TEST_F(VisualOdometryTest, ACoveredCameraHasNoBlobsAndIsInvalid) {
  VisualOdometry vo(camera_, options_);
  vo.UpdateFeatures(Utime(0), Frame(0), speed_, 0.0);
  const VisualMotion& m = vo.Update(Utime(1), std::span<const vision::Blob>{}, speed_, 0.0);
  EXPECT_FALSE(m.valid);
  EXPECT_EQ(m.features, 0);
}

TEST_F(VisualOdometryTest, FramesTooFarApartAreNotPaired) {
  VisualOdometry vo(camera_, options_);
  vo.UpdateFeatures(Utime(0), Frame(0), speed_, 0.0);
  const VisualMotion& m = vo.UpdateFeatures(Utime(0) + 1000000, Frame(1), speed_, 0.0);
  EXPECT_FALSE(m.valid);
  EXPECT_EQ(m.reason, "frames too far apart to pair");
}

TEST(VisualOdometryOptions, ExplainWhatIsWrong) {
  VisualOdometryOptions o;
  o.tracker.method = MotionMethod::kPaper;
  o.min_matches = 1;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 2U);
  EXPECT_EQ(e[0].key, "tracker.method");
  EXPECT_EQ(e[1].key, "min_matches");
}

}  // namespace
}  // namespace plantscale::motion
