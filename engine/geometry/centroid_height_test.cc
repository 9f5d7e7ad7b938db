#include "engine/geometry/centroid_height.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/common/rng.h"
#include "engine/geometry/test_cameras.h"

namespace plantscale::geometry {
namespace {

using testing::Degrees;
using testing::ThesisCamera;

// The solid's inequality tested at many heights along the ray.
bool HitsBySampling(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector2d& root,
                    const CropShape& s) {
  for (int k = 0; k <= 4000; ++k) {
    const double z = s.height_m * k / 4000.0;
    const Eigen::Vector2d q = o.head<2>() + (z - o.z()) / d.z() * d.head<2>() - root;
    const double rho2 = s.radius_m * s.radius_m * (1.0 - std::pow(1.0 - z / s.height_m, 2));
    if (q.squaredNorm() <= rho2) return true;
  }
  return false;
}

TEST(CentroidHeight, RayTestAgreesWithSamplingTheSolid) {
  const CropShape shape{0.14, 0.11};
  Rng rng(7);
  const Eigen::Vector3d o(0.0, 0.0, 1.5);
  const Eigen::Vector2d root(0.2, 1.6);
  int hits = 0;
  int disagreements = 0;
  for (int i = 0; i < 4000; ++i) {
    // Rays aimed at random points of a box around the plant.
    const Eigen::Vector3d target(root.x() + rng.Uniform(-0.2, 0.2),
                                 root.y() + rng.Uniform(-0.2, 0.2), rng.Uniform(0.0, 0.12));
    const Eigen::Vector3d d = target - o;
    const bool exact = RayHitsCrop(o, d, root, shape);
    hits += exact;
    // Sampling misses grazing rays by at most one step: count, do not fail on them.
    disagreements += exact != HitsBySampling(o, d, root, shape);
  }
  EXPECT_GT(hits, 800);
  EXPECT_LE(disagreements, 4);  // grazing rays within a 0.03 mm sampling step
}

TEST(CentroidHeight, LookingStraightDownTheCentroidIsTheRimDisc) {
  CameraOptions o = ThesisCamera();
  o.tilt_rad = Degrees(90.0);
  const CameraModel camera(o);
  const CropShape shape{0.14, 0.11};
  // Directly below the camera only the rim's disc (z = h) is seen.
  const auto h = SilhouetteCentroidHeight(camera, {0.0, 0.0}, shape, 80);
  ASSERT_TRUE(h);
  EXPECT_NEAR(*h, 0.11, 1e-9);
  // Off the nadir the near side of the bowl joins the silhouette and the
  // centroid's ray crosses the axis lower, the more so the further off.
  const auto near = SilhouetteCentroidHeight(camera, {0.0, 0.3}, shape, 80);
  const auto far = SilhouetteCentroidHeight(camera, {0.0, 0.6}, shape, 80);
  ASSERT_TRUE(near && far);
  EXPECT_LT(*near, 0.11 - 0.0005);
  EXPECT_LT(*far, *near - 0.002);
  EXPECT_GT(*far, 0.5 * 0.11);
}

TEST(CentroidHeight, TableFollowsTheModelOverTheImage) {
  const CameraModel camera(ThesisCamera());
  CentroidHeightOptions o;
  o.shape = {0.14, 0.112};
  const CentroidHeights heights(camera, o);
  // Between nodes the table is within 1 mm of the model at that pixel.
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(333.0, 411.0), Eigen::Vector2d(97.0, 250.0),
                                    Eigen::Vector2d(520.0, 77.0)}) {
    const auto root = camera.ImageToPlane(uv, heights.HeightAt(uv));
    ASSERT_TRUE(root);
    const auto model = SilhouetteCentroidHeight(camera, *root, o.shape, o.samples);
    ASSERT_TRUE(model);
    EXPECT_NEAR(heights.HeightAt(uv), *model, 0.001) << uv.transpose();
  }
  // Not one height over the view: near the horizon plants are seen more
  // obliquely (lower centroids); at the bottom of a 45° camera's image the
  // near side of the bowl is magnified most (lower again).
  const double middle = heights.HeightAt({320.0, 250.0});
  EXPECT_GT(middle, heights.HeightAt({320.0, 10.0}) + 0.005);
  EXPECT_GT(middle, heights.HeightAt({320.0, 470.0}) + 0.004);
  // Locate puts the centroid's ray at that height.
  const Eigen::Vector2d uv(300.0, 200.0);
  const auto p = heights.Locate(uv);
  ASSERT_TRUE(p);
  const auto back = camera.Project({p->x(), p->y(), heights.HeightAt(uv)});
  ASSERT_TRUE(back);
  EXPECT_NEAR((*back - uv).norm(), 0.0, 1e-9);
}

TEST(CentroidHeight, LocateJacobianMatchesFiniteDifferences) {
  const CameraModel camera(ThesisCamera());
  const CentroidHeights heights(camera, CentroidHeightOptions{});
  const Eigen::Vector2d uv(250.0, 300.0);
  const Eigen::Matrix2d j = heights.LocateJacobian(uv);
  for (int i = 0; i < 2; ++i) {
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    step(i) = 0.5;
    const Eigen::Vector2d fd = (*heights.Locate(uv + step) - *heights.Locate(uv - step)) / 1.0;
    // The height's own change over a pixel (about 0.05 mm) is left out of J:
    // it moves the point by under 0.1 mm per pixel against J's 2–8 mm.
    EXPECT_NEAR((fd - j.col(i)).norm(), 0.0, 1e-4) << i;
  }
}

TEST(CentroidHeight, RejectsABadShapeNamingTheKey) {
  CentroidHeightOptions o;
  o.shape.height_m = 0.0;
  try {
    CentroidHeights heights(CameraModel(ThesisCamera()), o);
    FAIL() << "expected InvalidOptionsError";
  } catch (const InvalidOptionsError& e) {
    ASSERT_EQ(e.errors().size(), 1U);
    EXPECT_EQ(e.errors()[0].key, "shape.height_m");
  }
}

}  // namespace
}  // namespace plantscale::geometry
