#include "engine/geometry/grid_model.h"

#include <gtest/gtest.h>

#include <set>

#include <cmath>

#include "engine/geometry/test_cameras.h"

namespace plantscale::geometry {
namespace {

using testing::Degrees;
using testing::DisturbedCamera;
using testing::ObliqueCamera;

GridState SomeState() { return GridState{0.031, 1.42, Degrees(2.5), 0.48, 0.44}; }

Eigen::Matrix<double, 2, 5> NumericStateJacobian(const auto& f, const GridState& s) {
  Eigen::Matrix<double, 2, 5> j;
  const Vector5d x = s.AsVector();
  for (int i = 0; i < 5; ++i) {
    Vector5d hi = x;
    Vector5d lo = x;
    hi(i) += 1e-6;
    lo(i) -= 1e-6;
    j.col(i) = (f(GridState::FromVector(hi)) - f(GridState::FromVector(lo))) / 2e-6;
  }
  return j;
}

TEST(GridModel, PlantPositionsFollowThesisEquations21And22AtZeroBearing) {
  GridState s = SomeState();
  s.bearing_rad = 0.0;
  const Eigen::Vector2d p = PlantInVehicle(s, 2, -1);
  EXPECT_NEAR(p.x(), -1 * 0.48 + 0.031, 1e-12);  // x = n r̄ + t_x
  EXPECT_NEAR(p.y(), 2 * 0.44 + 1.42, 1e-12);    // y = m l̄ + Y
}

TEST(GridModel, PlantInVehicleJacobianMatchesFiniteDifferences) {
  for (int m : {0, 1, 4}) {
    for (int n : {-1, 0, 1}) {
      const auto f = [&](const GridState& s) -> Eigen::Vector2d { return PlantInVehicle(s, m, n); };
      const auto numeric = NumericStateJacobian(f, SomeState());
      EXPECT_LT((PlantInVehicleJacobian(SomeState(), m, n) - numeric).norm(), 1e-7);
    }
  }
}

TEST(GridModel, ImageJacobianMatchesFiniteDifferences) {
  // Thesis eqs. 4.18–4.27, for the disturbed camera with a virtual plane.
  const GridModel model(CameraModel(DisturbedCamera()), GridModelOptions{});
  for (int m : {0, 2, 3}) {
    for (int n : {-1, 0, 1}) {
      const auto f = [&](const GridState& s) -> Eigen::Vector2d {
        return *model.ImageOfPlant(s, m, n);
      };
      const auto numeric = NumericStateJacobian(f, SomeState());
      const auto analytic = model.ImageOfPlantJacobian(SomeState(), m, n);
      EXPECT_LT((analytic - numeric).norm(), 1e-5 * numeric.norm())
          << "m=" << m << " n=" << n << "\n"
          << analytic << "\nvs\n"
          << numeric;
    }
  }
}

TEST(GridModel, ImageJacobianMatchesThesisEquation418AtZeroBearing) {
  // ∂x_f/∂t_x = (f/dx) / ((Ψ n r̄ − m l̄ − Y) sin φ + t_z), thesis eq. 4.18,
  // with the thesis frame mapped as in camera_model.h.
  const CameraModel camera(ObliqueCamera());
  const GridModel model(camera, GridModelOptions{});
  GridState s = SomeState();
  s.bearing_rad = 0.0;
  const CameraOptions& o = camera.options();
  const double phi = std::numbers::pi / 2.0 - o.tilt_rad;
  const double t_z = o.height_m / std::sin(o.tilt_rad);
  const double axis_y = o.height_m / std::tan(o.tilt_rad);
  const int m = 1;
  const double y_w = axis_y - (m * s.plant_spacing_m + s.forward_m);
  const double expected = o.focal_length_m / o.pixel_width_m / (-y_w * std::sin(phi) + t_z);
  EXPECT_NEAR(model.ImageOfPlantJacobian(s, m, 0)(0, 0), expected, 1e-9 * expected);
}

TEST(GridModel, PlantsInViewAreInsideTheImageAndIncludeThreeRows) {
  const GridModel model(CameraModel(ObliqueCamera()), GridModelOptions{});
  GridState s = SomeState();
  model.ShiftReference(s);
  const auto plants = model.PlantsInView(s);
  ASSERT_FALSE(plants.empty());
  bool rows[3] = {false, false, false};
  for (const GridPlant& p : plants) {
    EXPECT_TRUE(model.camera().InImage(p.image_px));
    rows[p.n + 1] = true;
  }
  EXPECT_TRUE(rows[0] && rows[1] && rows[2]);
}

// Plants whose leaves reach into the view: those in view, and those beyond
// its border with a point within the reach (along x or y) in the image;
// every other plant of the lines about the view is left out.
TEST(GridModel, PlantsReachingViewAddsThoseJustBeyondTheBorder) {
  const GridModel model(CameraModel(ObliqueCamera()), GridModelOptions{});
  const CameraModel& camera = model.camera();
  const double h = camera.options().virtual_plane_height_m, reach = 0.1;
  const auto in_image = [&](const Eigen::Vector2d& g) {
    const auto uv = camera.Project({g.x(), g.y(), h});
    return uv && camera.InImage(*uv);
  };
  int beyond = 0;
  // The vehicle at 20 places along one plant spacing.
  for (int step = 0; step < 20; ++step) {
    GridState s = SomeState();
    s.forward_m += step * s.plant_spacing_m / 20.0;
    model.ShiftReference(s);
    const auto in_view = model.PlantsInView(s);
    EXPECT_EQ(model.PlantsReachingView(s, 0.0).size(), in_view.size());
    const auto reaching = model.PlantsReachingView(s, reach);
    std::set<std::pair<int, int>> got;
    for (const GridPlant& p : reaching) got.insert({p.m, p.n});
    for (const GridPlant& p : in_view) EXPECT_TRUE(got.count({p.m, p.n})) << p.m << "," << p.n;
    int beyond_here = 0, near_here = 0;
    for (int m = -3; m < 60; ++m) {
      for (int n = -1; n <= 1; ++n) {
        const Eigen::Vector2d g = PlantInVehicle(s, m, n);
        if (g.y() - reach > GridModelOptions{}.max_range_m) continue;
        bool near = in_image(g);
        for (const Eigen::Vector2d& d : {Eigen::Vector2d(reach, 0), Eigen::Vector2d(-reach, 0),
                                         Eigen::Vector2d(0, reach), Eigen::Vector2d(0, -reach)}) {
          near = near || in_image(g + d);
        }
        EXPECT_EQ(got.count({m, n}) == 1, near) << "step " << step << " plant " << m << "," << n;
        beyond_here += near && !in_image(g);
        near_here += near;
      }
    }
    EXPECT_EQ(got.size(), reaching.size()) << step;  // no plant twice
    EXPECT_EQ(reaching.size(), static_cast<size_t>(near_here)) << step;
    beyond += beyond_here;
  }
  EXPECT_GT(beyond, 10);  // line −1 below the image, the far line above it, the outer rows
}

TEST(GridModel, ReferenceShiftKeepsLineZeroBottomMostAndPlantsFixed) {
  const GridModel model(CameraModel(ObliqueCamera()), GridModelOptions{});
  GridState s = SomeState();
  s.forward_m = 0.2;  // line 0 is below the bottom of the image
  const Eigen::Vector2d before = PlantInVehicle(s, 3, 0);
  const int shifted = model.ShiftReference(s);
  EXPECT_GT(shifted, 0);
  EXPECT_TRUE(model.LineInView(s, 0));
  EXPECT_FALSE(model.LineInView(s, -1));
  // The same physical plant is now line 3 − shifted: eq. 4.6 moves only the reference.
  EXPECT_LT((PlantInVehicle(s, 3 - shifted, 0) - before).norm(), 1e-12);
  EXPECT_EQ(model.ShiftReference(s), 0);  // idempotent
  // Backing up shifts the other way.
  s.forward_m += 2.0 * s.plant_spacing_m;
  EXPECT_EQ(model.ShiftReference(s), -2);
}

TEST(GridModel, ReferenceShiftTransitionIsThesisEquation48) {
  const Matrix5d a = GridModel::ReferenceShiftTransition(1);
  Matrix5d expected = Matrix5d::Identity();
  expected(1, 4) = 1.0;
  EXPECT_EQ(a, expected);
  // Applied to a state it moves Y by l̄.
  const Vector5d x = SomeState().AsVector();
  EXPECT_NEAR((a * x)(1), x(1) + x(4), 1e-12);
}

}  // namespace
}  // namespace plantscale::geometry
