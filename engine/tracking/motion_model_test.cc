#include "engine/tracking/motion_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/geometry/test_cameras.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/tracking/observation_model.h"

namespace plantscale::tracking {
namespace {

using geometry::GridState;

GridState Perturbed(const GridState& s, int i, double h) {
  geometry::Vector5d v = s.AsVector();
  v(i) += h;
  return GridState::FromVector(v);
}

TEST(MotionModel, StraightAlongTheRowsShortensY) {
  const GridState s{0.01, 0.4, 0.0, 0.475, 0.45};
  const MotionPrediction p = PredictGridMotion(s, {0.05, 0.05}, 1.5);
  EXPECT_NEAR(p.state.forward_m, 0.35, 1e-12);
  EXPECT_NEAR(p.state.offset_m, 0.01, 1e-12);
  EXPECT_NEAR(p.state.bearing_rad, 0.0, 1e-12);
}

TEST(MotionModel, EveryPlantMovesRigidlyWithTheVehicle) {
  // The grid does not move: each plant's vehicle-frame position after the
  // motion is the old one seen from the displaced, rotated vehicle.
  const GridState s{-0.03, 0.5, 0.05, 0.475, 0.45};
  const WheelIncrement u{0.048, 0.062};
  const double w = 1.5;
  const MotionPrediction p = PredictGridMotion(s, u, w);
  const double d = 0.5 * (u.left_m + u.right_m);
  const double a = (u.right_m - u.left_m) / w;
  const Eigen::Vector2d t(-d * std::sin(a / 2), d * std::cos(a / 2));
  Eigen::Matrix2d rot;
  rot << std::cos(a), std::sin(a), -std::sin(a), std::cos(a);
  for (int m = 0; m < 4; ++m) {
    for (int n = -1; n <= 1; ++n) {
      const Eigen::Vector2d expected = rot * (geometry::PlantInVehicle(s, m, n) - t);
      const Eigen::Vector2d got = geometry::PlantInVehicle(p.state, m, n);
      EXPECT_NEAR((expected - got).norm(), 0.0, 1e-12) << m << "," << n;
    }
  }
  EXPECT_NEAR(p.state.bearing_rad, s.bearing_rad + a, 1e-15);
}

TEST(MotionModel, JacobiansMatchFiniteDifferences) {
  const double h = 1e-6;
  for (const GridState& s : {GridState{0.02, 0.4, 0.03, 0.475, 0.45},
                             GridState{-0.1, 1.1, -0.2, 0.5, 0.42}}) {
    for (const WheelIncrement& u : {WheelIncrement{0.05, 0.05}, WheelIncrement{0.03, 0.09},
                                    WheelIncrement{-0.02, 0.01}}) {
      const MotionPrediction p = PredictGridMotion(s, u, 1.5);
      for (int i = 0; i < 5; ++i) {
        const geometry::Vector5d fd = (PredictGridMotion(Perturbed(s, i, h), u, 1.5).state.AsVector() -
                                       PredictGridMotion(Perturbed(s, i, -h), u, 1.5).state.AsVector()) /
                                      (2 * h);
        EXPECT_LT((fd - p.d_state.col(i)).cwiseAbs().maxCoeff(), 1e-7) << "state " << i;
      }
      for (int k = 0; k < 2; ++k) {
        WheelIncrement plus = u;
        WheelIncrement minus = u;
        (k == 0 ? plus.left_m : plus.right_m) += h;
        (k == 0 ? minus.left_m : minus.right_m) -= h;
        const geometry::Vector5d fd = (PredictGridMotion(s, plus, 1.5).state.AsVector() -
                                       PredictGridMotion(s, minus, 1.5).state.AsVector()) /
                                      (2 * h);
        EXPECT_LT((fd - p.d_wheels.col(k)).cwiseAbs().maxCoeff(), 1e-7) << "wheel " << k;
      }
    }
  }
}

TEST(ObservationModel, PlantWithOffsetJacobianMatchesFiniteDifferences) {
  const double h = 1e-7;
  const GridState s{0.02, 0.4, 0.07, 0.475, 0.45};
  const Eigen::Vector2d d(0.01, -0.02);
  for (int m = 0; m < 3; ++m) {
    for (int n = -1; n <= 1; ++n) {
      const Eigen::Matrix<double, 2, 7> j = PlantWithOffsetJacobian(s, m, n, d);
      for (int i = 0; i < 5; ++i) {
        const Eigen::Vector2d fd = (PlantWithOffset(Perturbed(s, i, h), m, n, d) -
                                    PlantWithOffset(Perturbed(s, i, -h), m, n, d)) /
                                   (2 * h);
        EXPECT_LT((fd - j.col(i)).cwiseAbs().maxCoeff(), 1e-7);
      }
      for (int i = 0; i < 2; ++i) {
        Eigen::Vector2d dp = d;
        Eigen::Vector2d dm = d;
        dp(i) += h;
        dm(i) -= h;
        const Eigen::Vector2d fd =
            (PlantWithOffset(s, m, n, dp) - PlantWithOffset(s, m, n, dm)) / (2 * h);
        EXPECT_LT((fd - j.col(5 + i)).cwiseAbs().maxCoeff(), 1e-7);
      }
      // Without an offset it is the grid model's own plant.
      EXPECT_LT((PlantWithOffset(s, m, n, Eigen::Vector2d::Zero()) -
                 geometry::PlantInVehicle(s, m, n)).norm(), 1e-15);
    }
  }
}

}  // namespace
}  // namespace plantscale::tracking

namespace plantscale::tracking {
namespace {

// The camera bounce a frame suffers, against its first-order model: the
// point the nominal camera reads where the bounced camera sees P.
TEST(ObservationModel, BounceJacobianMatchesTheCameraModel) {
  const geometry::CameraOptions nominal = geometry::testing::ThesisCamera();
  const geometry::CameraModel camera(nominal);
  const double eps = 1e-5;
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.0, 1.5), Eigen::Vector2d(0.4, 1.2),
                                   Eigen::Vector2d(-0.5, 2.2)}) {
    const Eigen::Matrix<double, 2, 3> j = BounceJacobian(p, nominal.height_m);
    const auto moved = [&](geometry::CameraOptions bounced) {
      const auto uv = geometry::CameraModel(bounced).Project({p.x(), p.y(), 0.0});
      return Eigen::Vector2d((*camera.ImageToPlane(*uv, 0.0) - p) / eps);
    };
    geometry::CameraOptions pitched = nominal;
    pitched.tilt_rad -= eps;  // pitch up: the camera looks farther ahead
    geometry::CameraOptions rolled = nominal;
    rolled.roll_rad += eps;
    geometry::CameraOptions raised = nominal;
    raised.height_m += eps;
    const Eigen::Vector2d fd_pitch = moved(pitched);
    const Eigen::Vector2d fd_roll = moved(rolled);
    const Eigen::Vector2d fd_height = moved(raised);
    // Signs follow the camera model's conventions up to the direction of
    // each angle; the nuisance state is zero-mean, so only magnitudes and
    // the relation between the two components matter.
    const double sp = fd_pitch.dot(j.col(0)) >= 0 ? 1.0 : -1.0;
    const double sr = fd_roll.dot(j.col(1)) >= 0 ? 1.0 : -1.0;
    EXPECT_LT((fd_pitch - sp * j.col(0)).norm(), 1e-3 * j.col(0).norm() + 1e-4) << p.transpose();
    EXPECT_LT((fd_roll - sr * j.col(1)).norm(), 1e-3 * j.col(1).norm() + 1e-4) << p.transpose();
    EXPECT_LT((fd_height - j.col(2)).norm(), 1e-4) << p.transpose();
  }
}

// The calibration's focal column against the camera model: a point seen by
// a camera whose true focal length is (1 + ε) f, located with f.
TEST(ObservationModel, FocalJacobianMatchesTheCameraModel) {
  const geometry::CameraOptions nominal = geometry::testing::ThesisCamera();
  const geometry::CameraModel camera(nominal);
  const double eps = 1e-6;
  geometry::CameraOptions longer = nominal;
  longer.focal_length_m *= 1.0 + eps;
  const geometry::CameraModel truth(longer);
  // (The optical axis meets the ground near (0, 1.5): no move there.)
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.1, 0.9), Eigen::Vector2d(0.4, 1.2),
                                   Eigen::Vector2d(-0.5, 2.2), Eigen::Vector2d(0.6, 3.0)}) {
    for (const double plane : {0.0, 0.1}) {
      const Eigen::Vector2d j = FocalJacobian(camera, p, plane);
      const auto uv = truth.Project({p.x(), p.y(), plane});
      ASSERT_TRUE(uv.has_value());
      const Eigen::Vector2d fd = (*camera.ImageToPlane(*uv, plane) - p) / eps;
      EXPECT_LT((fd - j).norm(), 1e-3 * j.norm()) << p.transpose() << " " << fd.transpose()
                                                  << " vs " << j.transpose();
      EXPECT_GT(j.norm(), 0.1) << "a 1 % focal error moves points by millimetres";
    }
  }
}

// The field's camera (virtual plane 0.1 m) and a crop of 0.14 m leaf-tip
// radius with its tips at 0.112 m: centroids located on its heights.
struct FieldObservation {
  geometry::CameraModel camera{[] {
    geometry::CameraOptions co = geometry::testing::ThesisCamera();
    co.virtual_plane_height_m = 0.1;
    return co;
  }()};
  geometry::CentroidHeights heights{camera, [] {
                                      geometry::CentroidHeightOptions ho;
                                      ho.shape = {0.14, 0.112};
                                      return ho;
                                    }()};
  TrackerOptions options;
  ObservationModel model{camera, options, &heights};
};

// The central difference of f (a vector or a number) at x along state i.
template <typename F>
auto CentralDifference(const F& f, const Eigen::VectorXd& x, int i) {
  const double h = 1e-6;
  Eigen::VectorXd hi = x;
  Eigen::VectorXd lo = x;
  hi(i) += h;
  lo(i) -= h;
  using Value = decltype(f(x));
  const Value d = (f(hi) - f(lo)) / (2 * h);
  return d;
}

// The whole prediction of a plant with its offset and its own centroid
// height δh, located on the crop's centroid heights: ∂/∂ every state.
TEST(ObservationModel, PredictionJacobianWithPlantHeightMatchesFiniteDifferences) {
  const FieldObservation field;
  const ObservationModel& model = field.model;
  // Core (t_x, Y, Ψ, r̄, l̄), the wheel scale k, then (δx, δy, δh).
  Eigen::VectorXd x(9);
  x << 0.02, 1.3, 0.03, 0.475, 0.45, -0.03, 0.01, -0.02, 0.015;
  const auto predict = [&](const Eigen::VectorXd& v) {
    return model.Predict(v, GridState::FromVector(v.head<5>()), 1, -1, 6);
  };
  const Prediction p = predict(x);
  ASSERT_EQ(p.jacobian.cols(), 9);
  for (int i = 0; i < 9; ++i) {
    const Eigen::Vector2d fd =
        CentralDifference([&](const Eigen::VectorXd& v) -> Eigen::Vector2d { return predict(v).value; }, x, i);
    // The located height's own slope over the ground (a few mm per metre)
    // times δh/(H − h) is left out of J: under 3e-4 here (J's entries reach 1.5).
    EXPECT_LT((fd - p.jacobian.col(i)).cwiseAbs().maxCoeff(), 3e-4) << "state " << i;
  }
  // A plant with δh = 0 is where the grid puts it.
  Eigen::VectorXd flat = x;
  flat(8) = 0.0;
  const GridState s = GridState::FromVector(flat.head<5>());
  EXPECT_LT((predict(flat).value - PlantWithOffset(s, 1, -1, flat.segment<2>(6))).norm(), 1e-12);
  // δh > 0 (a taller centroid) moves it away from the nadir.
  EXPECT_GT(p.value.norm(), PlantWithOffset(s, 1, -1, x.segment<2>(6)).norm());
}

// A strip of three plants touching along row +1 (TrackerOptions::
// merged_row_strips): its lateral position normalᵀ·mean(predictions), the
// normal held at the prediction, against ∂/∂ every state; the plants carry
// their own offsets and heights.
TEST(ObservationModel, StripAcrossItsRowMatchesFiniteDifferences) {
  const FieldObservation field;
  const ObservationModel& model = field.model;
  // Core (t_x, Y, Ψ, r̄, l̄), the wheel scale k, then (δx, δy, δh) of each plant.
  Eigen::VectorXd x(15);
  x << 0.02, 1.3, 0.03, 0.475, 0.45, -0.03, 0.01, -0.02, 0.015, -0.004, 0.006, -0.01, 0.003, 0.0, 0.02;
  const auto strip = [&](const Eigen::VectorXd& v) {
    std::vector<Prediction> plants;
    for (int m = 1; m <= 3; ++m) {
      plants.push_back(model.Predict(v, GridState::FromVector(v.head<5>()), m, 1, 6 + 3 * (m - 1)));
    }
    return PredictStrip(plants);
  };
  const StripPrediction p = strip(x);
  ASSERT_EQ(p.jacobian.cols(), 15);
  EXPECT_NEAR(p.normal.norm(), 1.0, 1e-12);
  // The normal is across the rows: the grid's bearing is 0.03 rad.
  EXPECT_NEAR(std::abs(p.normal.x()), std::cos(0.03), 0.01);
  for (int i = 0; i < 15; ++i) {
    const double fd =
        CentralDifference([&](const Eigen::VectorXd& v) { return p.normal.dot(strip(v).value); }, x, i);
    // As the single plant's test: the located height's slope is left out of J.
    EXPECT_NEAR(fd, p.normal.dot(p.jacobian.col(i)), 3e-4) << "state " << i;
  }
  // Each plant's own offset weighs a third.
  EXPECT_NEAR(std::abs(p.normal.dot(p.jacobian.col(6))), 1.0 / 3.0, 0.01);
  EXPECT_THROW(PredictStrip(std::vector<Prediction>(1)), std::invalid_argument);
}

}  // namespace
}  // namespace plantscale::tracking
