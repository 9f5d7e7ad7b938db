#include "engine/motion/mosaic.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "engine/motion/test_scenes.h"

namespace plantscale::motion {
namespace {

class MosaicTest : public ::testing::Test {
 protected:
  MosaicTest() : camera_(testing::SanchizPlaCamera()) {
    options_.min_m = {-0.5, 0.0};
    options_.max_m = {0.5, 1.5};
  }
  cv::Mat Labels(uint8_t value) const { return cv::Mat(576, 768, CV_8UC1, cv::Scalar(value)); }
  geometry::CameraModel camera_;
  MosaicOptions options_;
};

TEST_F(MosaicTest, CellsInTheFootprintTakeTheFrameLabelOthersStayUnknown) {
  Mosaic mosaic(options_, camera_);
  mosaic.AddFrame(Labels(kWeedLabel), VehiclePose2{});
  const MosaicMap map = mosaic.Build();
  EXPECT_EQ(map.LabelAt({0.0, 0.55}), kWeedLabel);
  EXPECT_EQ(map.LabelAt({0.0, 1.2}), kUnknownLabel);
  EXPECT_EQ(map.LabelAt({0.0, 0.1}), kUnknownLabel);
  EXPECT_EQ(map.labels.size(), map.grid.size());
  EXPECT_EQ(map.frames, 1);
}

TEST_F(MosaicTest, TheGridCoversTheExtentOnMultiplesOfTheResolution) {
  const MosaicMap map = Mosaic(options_, camera_).Build();
  EXPECT_DOUBLE_EQ(map.grid.resolution_m, 0.01);
  EXPECT_NEAR(map.grid.origin_m.x(), -0.5, 1e-12);
  EXPECT_NEAR(map.grid.origin_m.y(), 0.0, 1e-12);
  EXPECT_EQ(map.grid.cols, 101);
  EXPECT_EQ(map.grid.rows, 151);
  EXPECT_EQ(map.LabelAt({0.6, 0.5}), kUnknownLabel);  // outside the grid
}

TEST_F(MosaicTest, TheMajorityOfOverlappingFramesWins) {
  Mosaic mosaic(options_, camera_);
  mosaic.AddFrame(Labels(kSoilLabel), VehiclePose2{});
  mosaic.AddFrame(Labels(kWeedLabel), VehiclePose2{});
  mosaic.AddFrame(Labels(kSoilLabel), VehiclePose2{});
  EXPECT_EQ(mosaic.Build().LabelAt({0.0, 0.55}), kSoilLabel);
  EXPECT_EQ(mosaic.frames(), 3);
}

TEST_F(MosaicTest, APlantIsPlacedWithThePoseAndRegistered) {
  // A 7 cm disc of plant at (0.05, 0.55) seen from a pose 0.2 m forward.
  const VehiclePose2 pose{0.0, {0.0, 0.2}};
  const Eigen::Vector2d uv = *camera_.Project({0.05, 0.55, 0.0});
  cv::Mat labels = Labels(kSoilLabel);
  cv::circle(labels, cv::Point(static_cast<int>(uv.x()), static_cast<int>(uv.y())), 60,
             cv::Scalar(kPlantLabel), cv::FILLED);  // ≈ 3.6 cm radius
  Mosaic mosaic(options_, camera_);
  mosaic.AddFrame(labels, pose);
  const MosaicMap map = mosaic.Build();
  ASSERT_EQ(map.plants.size(), 1U);
  EXPECT_LT((map.plants[0].position_m - Eigen::Vector2d(0.05, 0.75)).norm(), 0.01);
  EXPECT_NEAR(map.plants[0].radius_m, 0.036, 0.005);
  EXPECT_EQ(map.LabelAt({0.05, 0.75}), kPlantLabel);
}

TEST_F(MosaicTest, APlantCutByTheEdgeOfTheViewIsNotRegistered) {
  const Eigen::Vector2d uv = *camera_.Project({0.0, 0.55, 0.0});
  cv::Mat labels = Labels(kSoilLabel);
  cv::circle(labels, cv::Point(0, static_cast<int>(uv.y())), 80, cv::Scalar(kPlantLabel), cv::FILLED);
  Mosaic mosaic(options_, camera_);
  mosaic.AddFrame(labels, VehiclePose2{});
  EXPECT_TRUE(mosaic.Build().plants.empty());
}

TEST_F(MosaicTest, AnExtentOfMoreThan32768CellsASideIsRejected) {
  options_.max_m = {0.5, 400.0};  // 40001 rows at 1 cm
  EXPECT_THROW(Mosaic(options_, camera_), InvalidOptionsError);
  options_.max_m = {0.5, 300.0};
  EXPECT_TRUE(options_.Validate().empty());
}

TEST_F(MosaicTest, LabelFrameSplitsPlantsFromWeedsBySize) {
  cv::Mat mask(576, 768, CV_8UC1, cv::Scalar(0));
  cv::rectangle(mask, cv::Rect(100, 100, 200, 200), cv::Scalar(255), cv::FILLED);
  cv::rectangle(mask, cv::Rect(500, 100, 20, 20), cv::Scalar(255), cv::FILLED);
  vision::BlobExtractor blobs({1, true});
  const auto found = blobs.Extract(mask, camera_);
  cv::Mat labels;
  LabelFrame(mask, found, [](const vision::Blob& b) { return b.area_px > 1000; }, labels);
  EXPECT_EQ(labels.at<uint8_t>(200, 200), kPlantLabel);
  EXPECT_EQ(labels.at<uint8_t>(110, 510), kWeedLabel);
  EXPECT_EQ(labels.at<uint8_t>(400, 400), kSoilLabel);
}

}  // namespace
}  // namespace plantscale::motion
