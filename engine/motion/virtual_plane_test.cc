#include "engine/motion/virtual_plane.h"

#include <gtest/gtest.h>

#include "engine/motion/test_scenes.h"

namespace plantscale::motion {
namespace {

// Eq. 1 scaled by v / f (eq. 8) is the ground point the CameraModel finds:
// x to the right, and y_vc = −y (the virtual camera's y points back).
TEST(VirtualPlane, EquationOneMatchesTheCameraModelOnTheGround) {
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  const auto& o = camera.options();
  const double off_vertical = M_PI / 2.0 - o.tilt_rad;
  for (const Eigen::Vector2d& ground : {Eigen::Vector2d(0.0, 0.534), Eigen::Vector2d(0.15, 0.4),
                                        Eigen::Vector2d(-0.18, 0.68)}) {
    const Eigen::Vector2d uv = *camera.Project({ground.x(), ground.y(), 0.0});
    const Eigen::Vector2d xy_c((uv.x() - camera.principal_point().x()) * o.pixel_width_m,
                               (uv.y() - camera.principal_point().y()) * o.pixel_height_m);
    const auto vc = VirtualImagePoint(xy_c, o.focal_length_m, off_vertical);
    ASSERT_TRUE(vc.has_value());
    const double scale = o.height_m / o.focal_length_m;
    EXPECT_NEAR(vc->x() * scale, ground.x(), 1e-9);
    EXPECT_NEAR(-vc->y() * scale, ground.y(), 1e-9);
    const auto plane = ImageToFeaturePlane(camera, uv, 0.0);
    ASSERT_TRUE(plane.has_value());
    EXPECT_LT((*plane - ground).norm(), 1e-9);
  }
}

TEST(VirtualPlane, RaysAboveTheHorizonDoNotReachTheVirtualPlane) {
  // 60° off vertical: a ray 35° above the axis points above the horizon.
  EXPECT_FALSE(VirtualImagePoint({0.0, -0.04 * std::tan(0.61)}, 0.04, 1.0472).has_value());
}

// A feature plane at height h is the ground plane shrunk towards the nadir
// by (v − h) / v: the depth z_vc of eq. 8 is v − h.
TEST(VirtualPlane, FeaturePlaneAtPlantHeightScalesTowardsTheNadir) {
  const geometry::CameraModel camera(testing::SanchizPlaCamera());
  const Eigen::Vector2d uv(200.0, 100.0);
  const Eigen::Vector2d ground = *ImageToFeaturePlane(camera, uv, 0.0);
  const Eigen::Vector2d top = *ImageToFeaturePlane(camera, uv, 0.056);
  EXPECT_LT((top - ground * (1.2 - 0.056) / 1.2).norm(), 1e-9);
}

}  // namespace
}  // namespace plantscale::motion
