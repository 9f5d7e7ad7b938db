#include "engine/tracking/observation_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/geometry/test_cameras.h"
#include "engine/tracking/observation_test_fixture.h"

// The plant point model's Jacobians (observation_model.h) against finite
// differences and against the camera model.

namespace plantscale::tracking {
namespace {

using geometry::GridState;
using testing::CentralDifference;
using testing::FieldObservation;

GridState Perturbed(const GridState& s, int i, double h) {
  geometry::Vector5d v = s.AsVector();
  v(i) += h;
  return GridState::FromVector(v);
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

}  // namespace
}  // namespace plantscale::tracking
