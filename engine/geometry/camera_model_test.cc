#include "engine/geometry/camera_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/geometry/test_cameras.h"

namespace plantscale::geometry {
namespace {

using testing::Degrees;
using testing::DisturbedCamera;
using testing::ObliqueCamera;

// Central finite difference of f: R^N -> R^M at x.
template <int M, int N, typename F>
Eigen::Matrix<double, M, N> NumericJacobian(F f, const Eigen::Matrix<double, N, 1>& x,
                                            double step) {
  Eigen::Matrix<double, M, N> j;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> hi = x;
    Eigen::Matrix<double, N, 1> lo = x;
    hi(i) += step;
    lo(i) -= step;
    j.col(i) = (f(hi) - f(lo)) / (2.0 * step);
  }
  return j;
}

TEST(CameraModel, RejectsInvalidOptionsNamingTheKey) {
  CameraOptions o = ObliqueCamera();
  o.height_m = -1.0;
  o.tilt_rad = Degrees(95.0);
  o.image_width_px = 0;
  try {
    CameraModel camera(o);
    FAIL() << "expected InvalidOptionsError";
  } catch (const InvalidOptionsError& e) {
    ASSERT_EQ(e.errors().size(), 3U);
    EXPECT_EQ(e.errors()[0].key, "height_m");
    EXPECT_EQ(e.errors()[1].key, "tilt_rad");
    EXPECT_EQ(e.errors()[2].key, "image_width_px");
  }
  o = ObliqueCamera();
  o.tilt_rad = 0.0;  // looking at the horizon: excluded, (0, 90°]
  EXPECT_THROW(CameraModel{o}, InvalidOptionsError);
  o.tilt_rad = Degrees(90.0);  // straight down: allowed
  EXPECT_NO_THROW(CameraModel{o});
}

TEST(CameraModel, OpticalAxisHitsTheGroundAtThePrincipalPoint) {
  const CameraModel camera(ObliqueCamera());
  const double h = camera.options().height_m;
  const double ahead = h / std::tan(camera.options().tilt_rad);
  const auto uv = camera.Project({0.0, ahead, 0.0});
  ASSERT_TRUE(uv.has_value());
  EXPECT_NEAR(uv->x(), 322.5, 1e-9);
  EXPECT_NEAR(uv->y(), 236.0, 1e-9);
  // Points further ahead appear higher in the image; points to the right, right.
  EXPECT_LT(camera.Project({0.0, ahead + 1.0, 0.0})->y(), uv->y());
  EXPECT_GT(camera.Project({0.3, ahead, 0.0})->x(), uv->x());
}

TEST(CameraModel, MatchesThesisEquations25And26AtZeroBearing) {
  // Thesis eqs. 2.5–2.6 use φ from the vertical, t_z along the optical axis
  // and a world y axis pointing back from the optical axis' ground point.
  const CameraModel camera(ObliqueCamera());
  const CameraOptions& o = camera.options();
  const double phi = std::numbers::pi / 2.0 - o.tilt_rad;
  const double t_z = o.height_m / std::sin(o.tilt_rad);
  const double axis_y = o.height_m / std::tan(o.tilt_rad);
  for (double x : {-0.6, 0.0, 0.45}) {
    for (double y : {1.0, 1.8, 3.0}) {
      const double x_w = x;
      const double y_w = axis_y - y;
      const double den = -y_w * std::sin(phi) + t_z;
      const double x_f = o.focal_length_m / o.pixel_width_m * x_w / den + 322.5;
      const double y_f = o.focal_length_m / o.pixel_height_m * y_w * std::cos(phi) / den + 236.0;
      const auto uv = camera.Project({x, y, 0.0});
      ASSERT_TRUE(uv.has_value());
      EXPECT_NEAR(uv->x(), x_f, 1e-9);
      EXPECT_NEAR(uv->y(), y_f, 1e-9);
    }
  }
}

TEST(CameraModel, ProjectJacobianMatchesFiniteDifferences) {
  const CameraModel camera(DisturbedCamera());
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.1, 1.5, 0.0), Eigen::Vector3d(-0.7, 2.4, 0.2),
                                   Eigen::Vector3d(0.9, 3.5, 0.05)}) {
    const auto f = [&](const Eigen::Vector3d& q) -> Eigen::Vector2d { return *camera.Project(q); };
    const Eigen::Matrix<double, 2, 3> numeric = NumericJacobian<2, 3>(f, p, 1e-6);
    EXPECT_LT((camera.ProjectJacobian(p) - numeric).norm(), 1e-5 * numeric.norm())
        << camera.ProjectJacobian(p) << "\nvs\n"
        << numeric;
  }
}

TEST(CameraModel, ImageToPlaneRoundTripsWithProject) {
  const CameraModel camera(DisturbedCamera());
  for (double plane : {0.0, 0.12}) {
    for (double u : {10.0, 320.0, 631.0}) {
      for (double v : {150.0, 240.0, 470.0}) {
        const auto ground = camera.ImageToPlane({u, v}, plane);
        ASSERT_TRUE(ground.has_value());
        const auto uv = camera.Project({ground->x(), ground->y(), plane});
        ASSERT_TRUE(uv.has_value());
        EXPECT_NEAR(uv->x(), u, 1e-9);
        EXPECT_NEAR(uv->y(), v, 1e-9);
      }
    }
  }
}

TEST(CameraModel, ImageToPlaneJacobianMatchesFiniteDifferences) {
  const CameraModel camera(DisturbedCamera());
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(40.0, 400.0), Eigen::Vector2d(320.0, 240.0),
                                    Eigen::Vector2d(600.0, 120.0)}) {
    const auto f = [&](const Eigen::Vector2d& q) -> Eigen::Vector2d {
      return *camera.ImageToPlane(q, 0.12);
    };
    const Eigen::Matrix2d numeric = NumericJacobian<2, 2>(f, uv, 1e-4);
    EXPECT_LT((camera.ImageToPlaneJacobian(uv, 0.12) - numeric).norm(), 1e-6 * numeric.norm());
    // It is the inverse of the forward Jacobian restricted to the plane.
    const Eigen::Vector2d g = f(uv);
    const Eigen::Matrix2d forward = camera.ProjectJacobian({g.x(), g.y(), 0.12}).leftCols<2>();
    EXPECT_LT(
        (camera.ImageToPlaneJacobian(uv, 0.12) * forward - Eigen::Matrix2d::Identity()).norm(),
        1e-9);
  }
}

TEST(CameraModel, RaysAboveTheHorizonNeverReachTheGround) {
  CameraOptions o = ObliqueCamera();
  o.tilt_rad = Degrees(10.0);  // shallow: the horizon is inside the image
  const CameraModel camera(o);
  const double horizon = camera.HorizonV();
  ASSERT_GT(horizon, 0.0);
  ASSERT_LT(horizon, 480.0);
  EXPECT_FALSE(camera.ImageToPlane({320.0, horizon - 2.0}, 0.0).has_value());
  EXPECT_TRUE(camera.ImageToPlane({320.0, horizon + 2.0}, 0.0).has_value());
  EXPECT_FALSE(camera.Project({0.0, -1.0, 0.0}).has_value());  // behind the camera
}

TEST(CameraModel, HomographyAgreesWithProject) {
  const CameraModel camera(DisturbedCamera());
  const Eigen::Matrix3d h = camera.PlaneToImageHomography(0.12);
  const Eigen::Vector3d p(0.3, 2.1, 0.12);
  const Eigen::Vector3d w = h * Eigen::Vector3d(p.x(), p.y(), 1.0);
  const Eigen::Vector2d uv = *camera.Project(p);
  EXPECT_NEAR(w.x() / w.z(), uv.x(), 1e-9);
  EXPECT_NEAR(w.y() / w.z(), uv.y(), 1e-9);
}

}  // namespace
}  // namespace plantscale::geometry
