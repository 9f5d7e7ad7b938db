#include "engine/tracking/initialiser.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/geometry/centroid_height.h"
#include "engine/tracking/blob_features.h"
#include "engine/tracking/test_scene.h"

namespace plantscale::tracking {
namespace {

TEST(Initialiser, HoughFindsTheRowsAmongWeeds) {
  testing::TestScene scene;
  scene.truth = {0.07, 0.21, -0.05, 0.475, 0.45};
  scene.weeds_per_frame = 15;
  const auto features = scene.Features();
  InitialiserOptions o;
  const auto fit = FitRowsOnGround(features, 0.475, 1, o);
  ASSERT_TRUE(fit);
  // Tolerances: a quarter of the thesis's Hough resolution (16 mm, 0.5°).
  EXPECT_NEAR(fit->offset_m, 0.07, 0.004);
  EXPECT_NEAR(fit->bearing_rad, -0.05, 0.002);
  EXPECT_GT(fit->support, 0.6);
  const auto phase = PlantLinePhaseOnGround(features, *fit, 0.475, 0.45, 1, o);
  ASSERT_TRUE(phase);
  EXPECT_NEAR(std::remainder(phase->forward_m - 0.21, 0.45), 0.0, 0.01);
  EXPECT_GT(phase->coherence, 0.8);
}

TEST(Initialiser, RefusesFeaturesWithoutRows) {
  testing::TestScene scene;
  scene.truth.offset_m = 5.0;  // no crop in view
  scene.weeds_per_frame = 30;
  InitialiserOptions o;
  GridInitialiser init(o, 0.475, 0.45, 1, 1.5);
  for (int frame = 0; frame < 5; ++frame) {
    const auto features = scene.Features();
    const InitialiserResult r = init.Offer(features, {0.05, 0.05});
    EXPECT_FALSE(r.state) << "frame " << frame;
    EXPECT_FALSE(r.reason.empty());
  }
}

TEST(Initialiser, ConfirmsOnTheThirdAgreeingFrame) {
  testing::TestScene scene;
  scene.truth = {-0.04, 0.3, 0.03, 0.475, 0.45};
  GridInitialiser init(InitialiserOptions{}, 0.475, 0.45, 1, 1.5);
  const WheelIncrement u{0.056, 0.056};
  InitialiserResult first = init.Offer(scene.Features(), {});
  EXPECT_FALSE(first.state);
  EXPECT_NE(first.reason.find("waiting"), std::string::npos);
  scene.Drive(u);
  EXPECT_FALSE(init.Offer(scene.Features(), u).state);
  scene.Drive(u);
  const InitialiserResult second = init.Offer(scene.Features(), u);
  ASSERT_TRUE(second.state);
  EXPECT_NEAR(second.state->offset_m, scene.truth.offset_m, 0.005);
  EXPECT_NEAR(second.state->bearing_rad, scene.truth.bearing_rad, 0.003);
  EXPECT_NEAR(std::remainder(second.state->forward_m - scene.truth.forward_m, 0.45), 0.0, 0.01);
}


// A closed canopy (the `treatment` preset's kind): each row one long blob
// cut by the image's border, and beside them a few leaves and weeds seen
// apart that happen to line up at 12°. The centroids alone give the wrong
// bearing; the bands' axes give the rows'.
std::vector<Feature> ClosedCanopy(double offset_m, double bearing_rad, double r, double elongation) {
  std::vector<Feature> features;
  const Eigen::Vector2d along(std::sin(bearing_rad), std::cos(bearing_rad));
  for (int n = -1; n <= 1; ++n) {
    Feature band;
    const double y = 1.6 + 0.1 * n;
    band.ground_m = {offset_m + n * r / std::cos(bearing_rad) + y * std::tan(bearing_rad), y};
    band.area_m2 = 0.35;
    band.clipped = true;
    band.axis_m = 0.7 * along;
    band.elongation = elongation;
    features.push_back(band);
  }
  for (int k = 0; k < 6; ++k) {  // small leaves and weeds on a line at 12°
    Feature f;
    const double y = 0.8 + 0.25 * k;
    f.ground_m = {-0.2 + y * std::tan(0.21), y};
    f.area_m2 = 0.004;
    f.axis_m = {0.02, 0.0};
    f.elongation = 1.2;
    features.push_back(f);
  }
  return features;
}

TEST(Initialiser, OnAClosedCanopyTheBandsGiveTheRowsBearing) {
  const double r = 0.5, offset = 0.03, bearing = 0.04;
  const InitialiserOptions o;
  const auto fit = FitRowsOnGround(ClosedCanopy(offset, bearing, r, 8.0), r, 1, o);
  ASSERT_TRUE(fit);
  EXPECT_TRUE(fit->closed_canopy);
  // The bands' axes are exact here: the fit keeps them to a tenth of a degree.
  EXPECT_NEAR(fit->bearing_rad, bearing, 0.002);
  EXPECT_NEAR(fit->offset_m, offset, 0.005);
  // Blobs not long enough to be bands: the Hough of what is seen apart
  // follows the leaves (the failure the bands cure).
  const auto blind = FitRowsOnGround(ClosedCanopy(offset, bearing, r, 1.5), r, 1, o);
  ASSERT_TRUE(blind);
  EXPECT_FALSE(blind->closed_canopy);
  EXPECT_GT(std::abs(blind->bearing_rad - bearing), 0.05);
}

// A blob's major axis on the ground: an image blob stretched along the
// image of a row is carried to the ground along that row.
TEST(BlobFeatures, TheMajorAxisRunsAlongTheRowOnTheGround) {
  const geometry::CameraModel camera(geometry::testing::ThesisCamera());
  const geometry::CentroidHeights heights(camera, geometry::CentroidHeightOptions{});
  // Two ground points on a row at 0.1 rad to the forward axis, their image.
  const double psi = 0.1;
  const double h = heights.HeightAt(camera.principal_point());
  const Eigen::Vector2d g0(0.2, 1.3), g1 = g0 + 0.4 * Eigen::Vector2d(std::sin(psi), std::cos(psi));
  const auto u0 = camera.Project({g0.x(), g0.y(), h});
  const auto u1 = camera.Project({g1.x(), g1.y(), h});
  ASSERT_TRUE(u0 && u1);
  vision::Blob b;
  b.on_ground = true;
  b.centroid_px = 0.5 * (*u0 + *u1);
  const Eigen::Vector2d d = (*u1 - *u0).normalized();
  const Eigen::Vector2d n(-d.y(), d.x());
  b.covariance_px2 = 400.0 * d * d.transpose() + 9.0 * n * n.transpose();  // σ 20 px along, 3 across
  b.bbox_px = cv::Rect(100, 100, 50, 50);
  b.ground_area_m2 = 0.05;
  std::vector<Feature> out;
  FeaturesFromBlobs(std::span<const vision::Blob>(&b, 1), camera.width(), camera.height(), out, &heights);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].elongation, 20.0 / 3.0, 1e-9);
  const Eigen::Vector2d axis = out[0].axis_m.y() < 0 ? Eigen::Vector2d(-out[0].axis_m) : out[0].axis_m;
  // The heights' table bends the plane a little over the blob: 0.5°.
  EXPECT_NEAR(std::atan2(axis.x(), axis.y()), psi, 0.009);
  EXPECT_GT(axis.norm(), 0.0);
}

}  // namespace
}  // namespace plantscale::tracking
