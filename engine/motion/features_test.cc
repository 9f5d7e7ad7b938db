#include "engine/motion/features.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "engine/motion/test_scenes.h"
#include "engine/vision/blobs.h"

namespace plantscale::motion {
namespace {

// Fig. 7 at the corner of an anticlockwise square: 90° convex, bisector
// pointing out of the corner.
TEST(Features, ConvexityAndOrientationAtASquareCorner) {
  double alpha = 0.0, beta = 0.0;
  ConvexityOrientation({0.0, -1.0}, {0.0, 0.0}, {-1.0, 0.0}, 1.0, alpha, beta);
  EXPECT_NEAR(alpha, M_PI / 2.0, 1e-12);
  EXPECT_NEAR(beta, M_PI / 4.0, 1e-12);
  // The same corner walked the other way round a hole is concave.
  ConvexityOrientation({-1.0, 0.0}, {0.0, 0.0}, {0.0, -1.0}, 1.0, alpha, beta);
  EXPECT_NEAR(alpha, -M_PI / 2.0, 1e-12);
}

std::vector<Eigen::Vector2d> Square(double side_m, int per_side) {
  std::vector<Eigen::Vector2d> c;
  const Eigen::Vector2d corners[] = {{0, 0}, {side_m, 0}, {side_m, side_m}, {0, side_m}};
  for (int k = 0; k < 4; ++k) {
    for (int i = 0; i < per_side; ++i)
      c.push_back(corners[k] + (corners[(k + 1) % 4] - corners[k]) * i / per_side);
  }
  return c;
}

TEST(Features, DominantPointsOfASquareAreItsCorners) {
  const auto square = Square(0.1, 50);
  std::vector<uint8_t> cut(square.size(), 0);
  FeatureOptions o;
  const std::vector<int> points = DominantPoints(square, cut, o);
  ASSERT_EQ(points.size(), 4U);
  for (int i : points) EXPECT_EQ(i % 50, 0) << "index " << i;  // exactly on a corner
  // A corner whose arms reach the image edge is a cut, not a feature.
  cut[10] = 1;
  EXPECT_EQ(DominantPoints(square, cut, o).size(), 3U);
}

TEST(Features, ExtractorFindsTheCornersOfASquarePlantOnTheGround) {
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  cv::Mat mask(576, 768, CV_8UC1, cv::Scalar(0));
  std::vector<cv::Point> quad;
  std::vector<Eigen::Vector2d> corners{{-0.05, 0.5}, {0.05, 0.5}, {0.05, 0.6}, {-0.05, 0.6}};
  for (const auto& g : corners) {
    const Eigen::Vector2d uv = *camera.Project({g.x(), g.y(), 0.0});
    quad.emplace_back(static_cast<int>(uv.x()), static_cast<int>(uv.y()));
  }
  cv::fillConvexPoly(mask, quad, cv::Scalar(255));
  vision::BlobExtractor blobs({1, true});
  const auto found = blobs.Extract(mask, camera);
  ASSERT_EQ(found.size(), 1U);
  FeatureExtractor extractor(FeatureOptions{});
  const auto& features = extractor.Extract(found, camera);
  ASSERT_EQ(features.size(), 4U);
  for (const Feature& f : features) {
    double nearest = 1e9;
    for (const auto& c : corners) nearest = std::min(nearest, (f.position_m - c).norm());
    EXPECT_LT(nearest, 0.003);  // within 3 mm (pixel footprint ≈ 0.6 mm)
    EXPECT_NEAR(f.convexity_rad, M_PI / 2.0, 0.1);
    EXPECT_TRUE(f.on_plant);
  }
}

TEST(Features, WeedsGiveNoFeaturesWhenOnlyPlantsAreUsed) {
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  cv::Mat mask(576, 768, CV_8UC1, cv::Scalar(0));
  cv::rectangle(mask, cv::Rect(300, 300, 60, 60), cv::Scalar(255), cv::FILLED);  // ≈ 4 cm
  vision::BlobExtractor blobs({1, true});
  const auto found = blobs.Extract(mask, camera);
  FeatureOptions o;
  o.weed_features = false;
  FeatureExtractor plants_only(o);
  EXPECT_FALSE(plants_only.IsPlant(found[0])) << found[0].ground_area_m2 << " m2";
  EXPECT_TRUE(plants_only.Extract(found, camera).empty());
  o.weed_features = true;
  FeatureExtractor with_weeds(o);
  EXPECT_FALSE(with_weeds.Extract(found, camera).empty());
}

// Eq. 5: n_k = det + notdet + notview; 17 of the 20 that could have been
// seen before were: 85 %, the paper's figure for its detector.
TEST(Features, StabilityIsEquationFive) {
  EXPECT_NEAR(FeatureStability(30, 17, 10), 85.0, 1e-12);
  EXPECT_EQ(FeatureStability(5, 0, 5), 0.0);
}

TEST(Features, OptionsExplainWhatIsWrong) {
  FeatureOptions o;
  o.detection_arm_m = -1.0;
  o.characteristic_arm_fraction = 0.9;
  EXPECT_EQ(o.Validate().size(), 2U);
  EXPECT_THROW(FeatureExtractor{o}, InvalidOptionsError);
}

}  // namespace
}  // namespace plantscale::motion
