#include "engine/vision/blobs.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "engine/common/rng.h"
#include "engine/geometry/test_cameras.h"
#include "engine/vision/holes.h"

namespace plantscale::vision {
namespace {

TEST(Blobs, RectangleAreaCentroidBoxWithPixelCentreConvention) {
  cv::Mat mask(20, 30, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(4, 6, 10, 5)).setTo(255);
  BlobExtractor extractor;
  const auto blobs = extractor.Extract(mask);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(blobs[0].area_px, 50);
  // Pixels 4..13 have centres 4.5..13.5: mean 9.0; rows 6..10: mean 8.5.
  EXPECT_NEAR(blobs[0].centroid_px.x(), 9.0, 1e-12);
  EXPECT_NEAR(blobs[0].centroid_px.y(), 8.5, 1e-12);
  EXPECT_EQ(blobs[0].bbox_px, cv::Rect(4, 6, 10, 5));
  // Variance of a uniform run of n pixels: (n² − 1)/12.
  EXPECT_NEAR(blobs[0].covariance_px2(0, 0), (100.0 - 1.0) / 12.0, 1e-9);
  EXPECT_NEAR(blobs[0].covariance_px2(1, 1), (25.0 - 1.0) / 12.0, 1e-9);
  EXPECT_NEAR(blobs[0].covariance_px2(0, 1), 0.0, 1e-9);
}

TEST(Blobs, DiagonalNeighboursAreOneBlobAndIdsFollowRasterOrder) {
  cv::Mat mask(10, 10, CV_8UC1, cv::Scalar(0));
  mask.at<uint8_t>(2, 2) = 255;
  mask.at<uint8_t>(3, 3) = 255;  // 8-connected to (2, 2)
  mask.at<uint8_t>(1, 8) = 255;  // alone, but first in raster order
  BlobExtractor extractor;
  const auto blobs = extractor.Extract(mask);
  ASSERT_EQ(blobs.size(), 2u);
  EXPECT_EQ(blobs[0].id, 1);
  EXPECT_EQ(blobs[0].area_px, 1);
  EXPECT_NEAR(blobs[0].centroid_px.x(), 8.5, 1e-12);
  EXPECT_EQ(blobs[1].area_px, 2);
}

TEST(Blobs, UShapeJoinsLateAndMinimumAreaFilters) {
  cv::Mat mask(12, 12, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(1, 1, 2, 8)).setTo(255);  // left arm
  mask(cv::Rect(8, 1, 2, 8)).setTo(255);  // right arm
  mask(cv::Rect(1, 9, 9, 2)).setTo(255);  // joins them at the bottom
  mask.at<uint8_t>(5, 5) = 255;           // speck
  BlobExtractor all;
  EXPECT_EQ(all.Extract(mask).size(), 2u);
  BlobExtractor filtered({.min_area_px = 2, .trace_contours = false});
  const auto blobs = filtered.Extract(mask);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(blobs[0].area_px, 16 + 16 + 18 - 0);
}

// Every blob agrees with OpenCV's connected components on random masks.
TEST(Blobs, AgreeWithOpenCvConnectedComponentsOnRandomMasks) {
  Rng rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    cv::Mat noise(97, 131, CV_8UC1);
    for (int v = 0; v < noise.rows; ++v) {
      for (int u = 0; u < noise.cols; ++u) noise.at<uint8_t>(v, u) = rng.Bernoulli(0.45) ? 255 : 0;
    }
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(noise, labels, stats, centroids, 8, CV_32S);
    BlobExtractor extractor;
    const auto blobs = extractor.Extract(noise);
    ASSERT_EQ(static_cast<int>(blobs.size()), n - 1);
    for (const Blob& b : blobs) {
      int matches = 0;
      for (int l = 1; l < n; ++l) {
        const cv::Rect box(stats.at<int>(l, cv::CC_STAT_LEFT), stats.at<int>(l, cv::CC_STAT_TOP),
                           stats.at<int>(l, cv::CC_STAT_WIDTH), stats.at<int>(l, cv::CC_STAT_HEIGHT));
        if (box != b.bbox_px || stats.at<int>(l, cv::CC_STAT_AREA) != b.area_px) continue;
        // OpenCV's centroids count from pixel corners: ours are +0.5.
        if (std::abs(b.centroid_px.x() - centroids.at<double>(l, 0) - 0.5) > 1e-9) continue;
        if (std::abs(b.centroid_px.y() - centroids.at<double>(l, 1) - 0.5) > 1e-9) continue;
        ++matches;
      }
      EXPECT_GE(matches, 1) << "blob " << b.id << " has no OpenCV twin";
    }
  }
}

// Blobs from runs labelled elsewhere (the hull grower's labelling of the
// mask before growth) are those Extract finds in the mask itself.
TEST(Blobs, ExtractLabelledEqualsExtractOnTheSameMask) {
  Rng rng(9);
  const geometry::CameraModel camera(geometry::testing::ThesisCamera());
  HullGrower grower;
  for (int trial = 0; trial < 10; ++trial) {
    cv::Mat mask(camera.height(), camera.width(), CV_8UC1, cv::Scalar(0));
    for (int k = 0; k < 40; ++k) {
      cv::circle(mask, {static_cast<int>(rng.Uniform(0, mask.cols)), static_cast<int>(rng.Uniform(0, mask.rows))},
                 static_cast<int>(rng.Uniform(1, 25)), cv::Scalar(255), cv::FILLED);
    }
    const cv::Mat low(mask.size(), CV_8UC1, cv::Scalar(0));
    cv::Mat grown = mask.clone();
    grower.Grow(grown, low, 30);
    BlobExtractor direct({.min_area_px = 5}), labelled({.min_area_px = 5});
    const auto a = direct.Extract(mask, camera);
    const auto b = labelled.ExtractLabelled(grower.mask_runs(), grower.mask_parent(), &camera);
    ASSERT_EQ(a.size(), b.size()) << trial;
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].area_px, b[i].area_px);
      EXPECT_EQ(a[i].bbox_px, b[i].bbox_px);
      EXPECT_NEAR((a[i].centroid_px - b[i].centroid_px).norm(), 0.0, 1e-12);
      EXPECT_NEAR((a[i].covariance_px2 - b[i].covariance_px2).norm(), 0.0, 1e-9);
      EXPECT_EQ(a[i].on_ground, b[i].on_ground);
      EXPECT_NEAR(a[i].ground_area_m2, b[i].ground_area_m2, 1e-15);
    }
  }
  BlobExtractor traced({.min_area_px = 1, .trace_contours = true});
  EXPECT_ANY_THROW(traced.ExtractLabelled(grower.mask_runs(), grower.mask_parent()));
}

// A blob's core is the part of it an earlier mask held: two rectangles
// joined by grown pixels make one blob whose core is both rectangles.
TEST(Blobs, CoresAreThePixelsOfTheMaskBeforeGrowth) {
  cv::Mat core(20, 30, CV_8UC1, cv::Scalar(0));
  core(cv::Rect(2, 3, 4, 5)).setTo(255);   // 20 px, centre (4, 5.5)
  core(cv::Rect(10, 3, 6, 5)).setTo(255);  // 30 px, centre (13, 5.5)
  cv::Mat grown = core.clone();
  grown(cv::Rect(1, 2, 16, 7)).setTo(255);  // a ring and the bridge: one blob
  grown(cv::Rect(22, 12, 3, 3)).setTo(255);  // grown alone: no core
  BlobExtractor before, after;
  before.Extract(core);
  const auto blobs = after.Extract(grown);
  ASSERT_EQ(blobs.size(), 2u);
  EXPECT_EQ(CoreOf(blobs[0]).area_px, blobs[0].area_px);  // no cores set: the blob itself
  after.SetCores(before.runs());
  EXPECT_EQ(blobs[0].area_px, 16 * 7);
  EXPECT_EQ(blobs[0].core_area_px, 50);
  const BlobCore c = CoreOf(blobs[0]);
  EXPECT_NEAR(c.centroid_px.x(), (20.0 * 4.0 + 30.0 * 13.0) / 50.0, 1e-12);
  EXPECT_NEAR(c.centroid_px.y(), 5.5, 1e-12);
  // Rows 3..7 (variance (25 − 1)/12); along u the two rectangles' own
  // variances plus their centres' spread about the mean.
  const double mu = c.centroid_px.x();
  const double var_u = (20.0 * ((16.0 - 1.0) / 12.0 + (4.0 - mu) * (4.0 - mu)) +
                        30.0 * ((36.0 - 1.0) / 12.0 + (13.0 - mu) * (13.0 - mu))) / 50.0;
  EXPECT_NEAR(c.covariance_px2(0, 0), var_u, 1e-9);
  EXPECT_NEAR(c.covariance_px2(1, 1), 2.0, 1e-9);
  EXPECT_NEAR(c.covariance_px2(0, 1), 0.0, 1e-9);
  EXPECT_EQ(blobs[1].core_area_px, 0);
  EXPECT_EQ(CoreOf(blobs[1]).area_px, 0.0);
}

TEST(Blobs, ContourOfASquareAndItsFreemanCode) {
  cv::Mat mask(8, 8, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(2, 2, 3, 3)).setTo(255);
  BlobExtractor extractor({.min_area_px = 1, .trace_contours = true});
  const auto blobs = extractor.Extract(mask);
  ASSERT_EQ(blobs.size(), 1u);
  const std::vector<cv::Point> expected = {{2, 2}, {3, 2}, {4, 2}, {4, 3}, {4, 4},
                                           {3, 4}, {2, 4}, {2, 3}};
  EXPECT_EQ(blobs[0].contour, expected);
  std::vector<uint8_t> codes;
  FreemanChainCode(blobs[0].contour, codes);
  // Clockwise on screen: east, east, south, south, west, west, north, north.
  EXPECT_EQ(codes, (std::vector<uint8_t>{0, 0, 6, 6, 4, 4, 2, 2}));
}

TEST(Blobs, ContourLengthMatchesOpenCvOnAnEllipse) {
  cv::Mat mask(60, 80, CV_8UC1, cv::Scalar(0));
  cv::ellipse(mask, {40, 30}, {25, 15}, 20.0, 0.0, 360.0, 255, cv::FILLED);
  BlobExtractor extractor({.min_area_px = 1, .trace_contours = true});
  const auto blobs = extractor.Extract(mask);
  ASSERT_EQ(blobs.size(), 1u);
  std::vector<std::vector<cv::Point>> cv_contours;
  cv::findContours(mask.clone(), cv_contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  ASSERT_EQ(cv_contours.size(), 1u);
  EXPECT_EQ(blobs[0].contour.size(), cv_contours[0].size());
}

TEST(Blobs, BuffersAreReusedAcrossFrames) {
  cv::Mat mask(50, 50, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(5, 5, 10, 10)).setTo(255);
  mask(cv::Rect(30, 30, 10, 10)).setTo(255);
  BlobExtractor extractor({.min_area_px = 1, .trace_contours = true});
  const Blob* first = extractor.Extract(mask).data();
  const cv::Point* contour = extractor.Extract(mask)[0].contour.data();
  for (int i = 0; i < 5; ++i) {
    const auto blobs = extractor.Extract(mask);
    EXPECT_EQ(blobs.data(), first);
    EXPECT_EQ(blobs[0].contour.data(), contour);
  }
}

TEST(Blobs, ProjectedOntoTheVirtualGroundPlane) {
  const geometry::CameraOptions options = geometry::testing::ThesisCamera();
  const geometry::CameraModel camera(options);
  cv::Mat mask(options.image_height_px, options.image_width_px, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(300, 300, 20, 20)).setTo(255);
  BlobExtractor extractor;
  const auto blobs = extractor.Extract(mask, camera);
  ASSERT_EQ(blobs.size(), 1u);
  ASSERT_TRUE(blobs[0].on_ground);
  const auto expected = camera.ImageToVirtualPlane({310.0, 310.0});
  ASSERT_TRUE(expected.has_value());
  EXPECT_NEAR((blobs[0].ground_m - *expected).norm(), 0.0, 1e-12);
  const double det = camera.ImageToPlaneJacobian({310.0, 310.0},
                                                 options.virtual_plane_height_m).determinant();
  EXPECT_NEAR(blobs[0].ground_area_m2, 400.0 * std::abs(det), 1e-12);
}

}  // namespace
}  // namespace plantscale::vision
