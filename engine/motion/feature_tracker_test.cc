#include "engine/motion/feature_tracker.h"

#include <gtest/gtest.h>

#include <map>

#include "engine/motion/test_scenes.h"

namespace plantscale::motion {
namespace {

using testing::Observe;
using testing::SanchizPlaCamera;
using testing::ScatterPoints;

// A sequence over a scatter of ground features: 0.1 m per frame with a slow
// left turn, 1 mm feature noise.
class TrackerSequence : public ::testing::TestWithParam<MotionMethod> {
 protected:
  TrackerSequence() : camera_(SanchizPlaCamera()), points_(ScatterPoints(4.0, 330.0, 11)) {}

  TrackerOptions Options() const {
    TrackerOptions o;
    o.method = GetParam();
    o.initial_motion = truth_;
    return o;
  }
  std::vector<Feature> Frame(int k, std::vector<int>* ids = nullptr) {
    VehiclePose2 pose;
    for (int i = 0; i < k; ++i) pose = Compose(pose, truth_);
    return Observe(points_, pose, camera_, 0.001, rng_, ids);
  }

  const PlanarMotion truth_{-0.0005, {0.0002, -0.1}};
  geometry::CameraModel camera_;
  std::vector<testing::ScenePoint> points_;
  std::mt19937 rng_{7};
};

TEST_P(TrackerSequence, RecoversTheMotionAndEveryCorrespondence) {
  FeatureTracker tracker(Options(), camera_, 0.0);
  std::map<int64_t, int> point_of_track;
  int matches = 0, correct = 0;
  for (int k = 0; k < 20; ++k) {
    std::vector<int> ids;
    const auto features = Frame(k, &ids);
    ASSERT_GE(features.size(), 30U);
    const FrameMotion& m = tracker.Update(features);
    if (k > 0) {
      EXPECT_TRUE(m.locked) << "frame " << k << ": " << Name(m.loss);
      // 1 mm noise over ±0.2 m; the paper's filters (P₀ = R₁ = R₂) lag.
      EXPECT_NEAR(m.motion.psi_rad, truth_.psi_rad, GetParam() == MotionMethod::kPaper ? 0.004 : 0.0015)
          << "frame " << k;
      EXPECT_LT((m.motion.t_m - truth_.t_m).norm(), 0.002) << "frame " << k;
    }
    for (size_t i = 0; i < features.size(); ++i) {
      if (m.track_of_feature[i] >= 0) {
        ++matches;
        correct += point_of_track[m.track_of_feature[i]] == ids[i] ? 1 : 0;
      }
      point_of_track[m.new_track_of_feature[i]] = ids[i];
    }
  }
  EXPECT_GT(matches, 19 * 20);
  EXPECT_EQ(correct, matches);
  VehiclePose2 truth;
  for (int i = 0; i < 19; ++i) truth = Compose(truth, truth_);
  EXPECT_LT((tracker.pose().position_m - truth.position_m).norm(), 0.01);  // 1 cm over 1.9 m
}

TEST_P(TrackerSequence, AFeatureMissedForAFrameReturnsToItsTrack) {
  FeatureTracker tracker(Options(), camera_, 0.0);
  std::vector<int> ids;
  std::map<int, int64_t> track_of_point;
  auto record = [&](const FrameMotion& m) {
    for (size_t i = 0; i < ids.size(); ++i) track_of_point[ids[i]] = m.new_track_of_feature[i];
  };
  record(tracker.Update(Frame(0, &ids)));
  record(tracker.Update(Frame(1, &ids)));
  // Frame 2 misses the features of every third point.
  auto features = Frame(2, &ids);
  std::vector<int> missed;
  std::vector<Feature> kept;
  std::vector<int> kept_ids;
  for (size_t i = 0; i < features.size(); ++i) {
    if (ids[i] % 3 == 0) {
      missed.push_back(ids[i]);
    } else {
      kept.push_back(features[i]);
      kept_ids.push_back(ids[i]);
    }
  }
  ids = kept_ids;
  const auto before = track_of_point;
  ASSERT_TRUE(tracker.Update(kept).locked);

  const auto again = Frame(3, &ids);
  const FrameMotion& m = tracker.Update(again);
  ASSERT_TRUE(m.locked);
  int missed_then = 0, returned = 0;
  for (size_t i = 0; i < ids.size(); ++i) {
    // Away from the bottom edge (y ≈ 0.37 m), where it leaves the view.
    if (ids[i] % 3 != 0 || !before.count(ids[i]) || again[i].position_m.y() < 0.40) continue;
    ++missed_then;
    returned += m.track_of_feature[i] == before.at(ids[i]) ? 1 : 0;

  }
  EXPECT_GT(missed_then, 5);
  EXPECT_EQ(returned, missed_then);
}

// Bad input: each loses lock without throwing, and the next good pair locks.
TEST_P(TrackerSequence, AFrameWithoutFeaturesLosesLockAndRecovers) {
  FeatureTracker tracker(Options(), camera_, 0.0);
  tracker.Update(Frame(0));
  ASSERT_TRUE(tracker.Update(Frame(1)).locked);
  const FrameMotion& lost = tracker.Update({});
  EXPECT_FALSE(lost.locked);
  EXPECT_EQ(lost.loss, LockLoss::kNoFeatures);
  EXPECT_TRUE(tracker.Update(Frame(3)).locked);  // coasted tracks still match
  EXPECT_TRUE(tracker.Update(Frame(4)).locked);
}

TEST_P(TrackerSequence, AFrameOfAllNewFeaturesLosesLockAndRecovers) {
  if (GetParam() == MotionMethod::kPaper)
    GTEST_SKIP() << "the published method has no defence against chance matches";
  FeatureTracker tracker(Options(), camera_, 0.0);
  tracker.Update(Frame(0));
  ASSERT_TRUE(tracker.Update(Frame(1)).locked);
  const auto elsewhere = ScatterPoints(4.0, 330.0, 99);  // another field
  VehiclePose2 pose;
  for (int i = 0; i < 2; ++i) pose = Compose(pose, truth_);
  const FrameMotion& lost = tracker.Update(Observe(elsewhere, pose, camera_, 0.001, rng_));
  EXPECT_FALSE(lost.locked);
  EXPECT_TRUE(lost.loss == LockLoss::kTooFewMatches || lost.loss == LockLoss::kMotionJump)
      << Name(lost.loss);
  tracker.Update(Frame(3));
  EXPECT_TRUE(tracker.Update(Frame(4)).locked);
}

TEST_P(TrackerSequence, ADuplicateFrameLosesLockAndRecovers) {
  FeatureTracker tracker(Options(), camera_, 0.0);
  tracker.Update(Frame(0));
  const auto frame1 = Frame(1);
  ASSERT_TRUE(tracker.Update(frame1).locked);
  const FrameMotion& lost = tracker.Update(frame1);
  EXPECT_FALSE(lost.locked);
  EXPECT_EQ(lost.loss, LockLoss::kDuplicateFrame);
  tracker.Update(Frame(3));
  EXPECT_TRUE(tracker.Update(Frame(4)).locked);
}

TEST_P(TrackerSequence, AFrameFromAnotherCameraLosesLockAndRecovers) {
  FeatureTracker tracker(Options(), camera_, 0.0);
  tracker.Update(Frame(0));
  ASSERT_TRUE(tracker.Update(Frame(1)).locked);
  // The frame a wide-angle camera at another tilt saw, read as ours.
  geometry::CameraOptions other = SanchizPlaCamera();
  other.tilt_rad = 45.0 * M_PI / 180.0;
  other.focal_length_m = 0.012;
  const geometry::CameraModel wide(other);
  VehiclePose2 pose;
  for (int i = 0; i < 2; ++i) pose = Compose(pose, truth_);
  std::vector<Feature> wrong = Observe(points_, pose, wide, 0.001, rng_);
  for (Feature& f : wrong) f.position_m = *camera_.ImageToPlane(f.pixel, 0.0);
  const FrameMotion& lost = tracker.Update(wrong);
  EXPECT_FALSE(lost.locked) << "matched " << lost.coherent;
  tracker.Update(Frame(3));
  EXPECT_TRUE(tracker.Update(Frame(4)).locked);
}

INSTANTIATE_TEST_SUITE_P(Methods, TrackerSequence,
                         ::testing::Values(MotionMethod::kPaper, MotionMethod::kOurs),
                         [](const auto& p) { return std::string(Name(p.param)); });

TEST(FeatureTracker, OptionsExplainWhatIsWrong) {
  TrackerOptions o;
  o.min_matches = 1;
  o.hough.open_m = 0.001;
  EXPECT_EQ(o.Validate().size(), 2U);
  EXPECT_THROW(FeatureTracker(o, geometry::CameraModel(SanchizPlaCamera()), 0.0),
               InvalidOptionsError);
}

}  // namespace
}  // namespace plantscale::motion
