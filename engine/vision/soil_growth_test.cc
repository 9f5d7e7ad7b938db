#include "engine/vision/soil_growth.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "engine/common/rng.h"

namespace plantscale::vision {
namespace {

// Textured soil: mean 60, sd 8 grey levels, independent per pixel.
cv::Mat Soil(int width, int height, uint64_t seed) {
  Rng rng(seed);
  cv::Mat image(height, width, CV_8UC1);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      image.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(rng.Normal(60.0, 8.0));
    }
  }
  return image;
}

// A lit plant (disc of radius 15 at 200, in the mask) with a shaded rim
// (radius 15 to 20 at 120: half the lit leaf, 7 soil sds above the soil,
// not in the mask), on textured soil.
struct Scene {
  cv::Mat plant, mask, rim;
};
Scene PlantWithShadedRim(cv::Point centre, uint64_t seed) {
  Scene s;
  s.plant = Soil(160, 120, seed);
  s.mask = cv::Mat(s.plant.size(), CV_8UC1, cv::Scalar(0));
  s.rim = cv::Mat(s.plant.size(), CV_8UC1, cv::Scalar(0));
  cv::circle(s.rim, centre, 20, cv::Scalar(255), cv::FILLED);
  cv::circle(s.mask, centre, 15, cv::Scalar(255), cv::FILLED);
  s.rim.setTo(0, s.mask);
  s.plant.setTo(120, s.rim);
  s.plant.setTo(200, s.mask);
  return s;
}

TEST(SoilGrowth, AShadedRimIsGrownAndTheSoilAroundItIsNot) {
  Scene s = PlantWithShadedRim({60, 60}, 1);
  const cv::Mat before = s.mask.clone();
  SoilGrower grower;
  const int added = grower.Grow(s.plant, s.mask);
  const int rim = cv::countNonZero(s.rim);
  const int rim_grown = cv::countNonZero(s.mask & s.rim);
  const int soil_grown = cv::countNonZero(s.mask & ~s.rim & ~before);
  EXPECT_EQ(added, rim_grown + soil_grown);
  // The rim is 5 px wide, inside the 6-px reach; the 3×3 smoothing lowers
  // only its outer edge pixels (by a third at most: still ≥ 100).
  EXPECT_GE(rim_grown, static_cast<int>(0.97 * rim)) << rim_grown << " of " << rim;
  // Soil: the smoothed rim edge spills at most a pixel ring (2π·21 ≈ 132)
  // and noise above μ + 3σ (0.13 % of soil pixels) only where it touches.
  EXPECT_LE(soil_grown, 140);
  // What was plant stays plant.
  EXPECT_EQ(cv::countNonZero(before & ~s.mask), 0);
}

TEST(SoilGrowth, BrightSoilNotReachedFromABlobStaysSoil) {
  Scene s = PlantWithShadedRim({40, 60}, 2);
  // A bright stone 30 px from the rim and a bright patch around a blob
  // under min_area_px (a 4×4 speck: 16 px).
  s.plant(cv::Rect(110, 50, 10, 10)).setTo(130);
  s.plant(cv::Rect(130, 90, 12, 12)).setTo(130);
  s.plant(cv::Rect(134, 94, 4, 4)).setTo(200);
  s.mask(cv::Rect(134, 94, 4, 4)).setTo(255);
  SoilGrower grower;
  grower.Grow(s.plant, s.mask);
  const cv::Mat candidates = grower.Candidates();
  // Both are candidates (bright against their soil) ...
  EXPECT_EQ(cv::countNonZero(candidates(cv::Rect(112, 52, 6, 6))), 36);
  EXPECT_GT(cv::countNonZero(candidates(cv::Rect(131, 91, 10, 10))), 50);
  // ... but neither is reached from a blob of 30 px or more.
  EXPECT_EQ(cv::countNonZero(s.mask(cv::Rect(100, 40, 30, 30))), 0);
  EXPECT_EQ(cv::countNonZero(s.mask(cv::Rect(128, 88, 16, 16))), 16);
}

TEST(SoilGrowth, JudgingOnlyWithinReachOfABlobLosesNoGrowth) {
  // Plants whose shaded rims cross the 64-px words' edges (u = 64, 128)
  // where the blob itself does not, one across u = 192, others against the
  // image's right and bottom edges, and bright soil touching a rim: Grow judges only the pixels growth can get
  // to, so it must match a geodesic growth over the candidates judged
  // everywhere.
  cv::Mat plant = Soil(260, 150, 6);
  cv::Mat mask(plant.size(), CV_8UC1, cv::Scalar(0)), rim = mask.clone();
  for (const cv::Point centre : {cv::Point(50, 40), cv::Point(141, 100), cv::Point(190, 30),
                                 cv::Point(250, 90), cv::Point(100, 145)}) {
    cv::circle(rim, centre, 17, cv::Scalar(255), cv::FILLED);
    cv::circle(mask, centre, 12, cv::Scalar(255), cv::FILLED);
  }
  rim.setTo(0, mask);
  plant.setTo(120, rim);
  plant(cv::Rect(66, 36, 4, 8)).setTo(115);  // bright soil from the first rim on
  plant.setTo(200, mask);
  cv::Mat grown = mask.clone();
  SoilGrower grower;
  const int added = grower.Grow(plant, grown);
  // The reference: six 3×3 dilations of the blobs, each kept to the blobs
  // and the candidates.
  const cv::Mat allowed = mask | grower.Candidates();
  cv::Mat expected = mask.clone();
  for (int k = 0; k < grower.options().reach_px; ++k) {
    cv::dilate(expected, expected, cv::Mat::ones(3, 3, CV_8UC1));
    expected &= allowed;
  }
  EXPECT_GT(added, 2000);  // the rims: 5 × π(17² − 12²) ≈ 2280 px less the cut edges
  EXPECT_EQ(added, cv::countNonZero(expected) - cv::countNonZero(mask));
  EXPECT_EQ(cv::countNonZero(grown != expected), 0);
}

TEST(SoilGrowth, GrowthStopsAfterItsReach) {
  SoilGrowthOptions o;
  o.reach_px = 3;
  Scene s = PlantWithShadedRim({60, 60}, 3);
  SoilGrower grower(o);
  grower.Grow(s.plant, s.mask);
  // The disc of radius 15 grown by 3 steps of a 3×3 square stays within
  // radius 15 + 3·√2 < 20.
  cv::Mat far(s.mask.size(), CV_8UC1, cv::Scalar(255));
  cv::circle(far, {60, 60}, 20, cv::Scalar(0), cv::FILLED);
  EXPECT_EQ(cv::countNonZero(s.mask & far), 0);
  // And it did grow into the rim's inner part.
  cv::Mat inner(s.mask.size(), CV_8UC1, cv::Scalar(0));
  cv::circle(inner, {60, 60}, 17, cv::Scalar(255), cv::FILLED);
  EXPECT_EQ(cv::countNonZero(inner & ~s.mask), 0);
}

TEST(SoilGrowth, JoinsAreRefusedOnlyWhenAsked) {
  // Two blobs 10 px apart joined by a shaded bridge 6 px wide.
  cv::Mat plant = Soil(160, 120, 4);
  cv::Mat mask(plant.size(), CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(40, 40, 20, 20)).setTo(255);
  mask(cv::Rect(70, 40, 20, 20)).setTo(255);
  plant(cv::Rect(60, 47, 10, 6)).setTo(120);
  plant.setTo(200, mask);
  const cv::Rect bridge(61, 48, 8, 4);  // clear of the smoothing's edge
  cv::Mat joined = mask.clone();
  SoilGrower grower;
  grower.Grow(plant, joined);
  EXPECT_EQ(cv::countNonZero(joined(bridge)), bridge.area());
  SoilGrowthOptions o;
  o.join_min_area_px = 1000;
  cv::Mat apart = mask.clone();
  SoilGrower refusing(o);
  refusing.Grow(plant, apart);
  EXPECT_EQ(cv::countNonZero(apart(bridge)), 0);
}

TEST(SoilGrowth, BadOptionsAndImagesAreNamed) {
  SoilGrowthOptions bad;
  bad.z = -1.0;
  bad.window_cells = 4;
  bad.min_area_px = 0;
  try {
    SoilGrower g(bad);
    FAIL() << "invalid options accepted";
  } catch (const InvalidOptionsError& e) {
    ASSERT_EQ(e.errors().size(), 3u);
    EXPECT_EQ(e.errors()[0].key, "z");
    EXPECT_EQ(e.errors()[1].key, "window_cells");
    EXPECT_EQ(e.errors()[2].key, "min_area_px");
  }
  SoilGrower grower;
  cv::Mat mask(10, 10, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(grower.Grow(cv::Mat(10, 12, CV_8UC1, cv::Scalar(0)), mask), DataError);
  EXPECT_THROW(grower.Grow(cv::Mat(10, 10, CV_16UC1, cv::Scalar(0)), mask), DataError);
  // Off: nothing changes.
  SoilGrowthOptions off;
  off.z = 0.0;
  Scene s = PlantWithShadedRim({60, 60}, 5);
  const cv::Mat before = s.mask.clone();
  SoilGrower none(off);
  EXPECT_EQ(none.Grow(s.plant, s.mask), 0);
  EXPECT_EQ(cv::countNonZero(s.mask != before), 0);
}

}  // namespace
}  // namespace plantscale::vision
