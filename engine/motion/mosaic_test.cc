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
  const maps::CropMap map = mosaic.Build();
  EXPECT_EQ(map.ClassAt(map.grid().CellAt({0.0, 0.55})), maps::CellClass::kWeed);
  EXPECT_EQ(map.ClassAt(map.grid().CellAt({0.0, 1.2})), maps::CellClass::kUnknown);
  EXPECT_EQ(map.ClassAt(map.grid().CellAt({0.0, 0.1})), maps::CellClass::kUnknown);
}

TEST_F(MosaicTest, TheMajorityOfOverlappingFramesWins) {
  Mosaic mosaic(options_, camera_);
  mosaic.AddFrame(Labels(kSoilLabel), VehiclePose2{});
  mosaic.AddFrame(Labels(kWeedLabel), VehiclePose2{});
  mosaic.AddFrame(Labels(kSoilLabel), VehiclePose2{});
  EXPECT_EQ(mosaic.Build().ClassAt(mosaic.Build().grid().CellAt({0.0, 0.55})),
            maps::CellClass::kSoil);
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
  const maps::CropMap map = mosaic.Build();
  ASSERT_EQ(map.plants().size(), 1U);
  EXPECT_LT((map.plants()[0].position_m - Eigen::Vector2d(0.05, 0.75)).norm(), 0.01);
  EXPECT_EQ(map.plants()[0].kind, maps::PlantKind::kCrop);
}

TEST_F(MosaicTest, APlantCutByTheEdgeOfTheViewIsNotRegistered) {
  const Eigen::Vector2d uv = *camera_.Project({0.0, 0.55, 0.0});
  cv::Mat labels = Labels(kSoilLabel);
  cv::circle(labels, cv::Point(0, static_cast<int>(uv.y())), 80, cv::Scalar(kPlantLabel), cv::FILLED);
  Mosaic mosaic(options_, camera_);
  mosaic.AddFrame(labels, VehiclePose2{});
  EXPECT_TRUE(mosaic.Build().plants().empty());
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
