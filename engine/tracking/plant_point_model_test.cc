#include "engine/tracking/plant_point_model.h"

#include <gtest/gtest.h>

#include "engine/tracking/observation_test_fixture.h"

// The plant point on the filter's full state (plant_point_model.h): the
// grid, k, a persistent bounce, the calibration and the plant's own states,
// each column against finite differences.

namespace plantscale::tracking {
namespace {

using geometry::GridState;
using testing::CentralDifference;
using testing::FieldObservation;

struct FullState {
  FieldObservation field;
  StateLayout layout{[&] {
    field.options.camera_bounce_correlation_s = 0.3;
    field.options.calibration_pitch_sd_rad = 0.004;
    field.options.calibration_roll_sd_rad = 0.004;
    field.options.calibration_height_sd_m = 0.01;
    field.options.calibration_focal_sd = 0.01;
    return StateLayout(field.options);
  }()};
};

// x: core (t_x, Y, Ψ, r̄, l̄), k, bounce (3), calibration (4), the plant's
// (δx, δy, δh) at 13; bounce and calibration as given.
Eigen::VectorXd StateWith(const Eigen::Vector3d& bounce, const Eigen::Vector4d& calibration) {
  Eigen::VectorXd x(16);
  x << 0.02, 1.3, 0.03, 0.475, 0.45, -0.03, bounce, calibration, -0.02, 0.015, 0.01;
  return x;
}

TEST(PlantPointModel, EveryColumnOfTheFullStateMatchesFiniteDifferences) {
  const FullState full;
  ASSERT_EQ(full.layout.bounce_index(), 6);
  ASSERT_EQ(full.layout.calibration_index(), 9);
  ASSERT_EQ(full.layout.head(), 13);
  const auto predict = [&](const Eigen::VectorXd& v) {
    return PredictPlant(full.field.model, full.layout, v, GridState::FromVector(v.head<5>()), 1, -1, 13);
  };
  // At zero bounce and calibration: exact to the located height's slope
  // (as ObservationModel's own test, observation_model_test.cc).
  const Eigen::VectorXd x0 = StateWith(Eigen::Vector3d::Zero(), Eigen::Vector4d::Zero());
  const Prediction p0 = predict(x0);
  ASSERT_EQ(p0.jacobian.cols(), 16);
  for (int i = 0; i < 16; ++i) {
    const Eigen::Vector2d fd = CentralDifference(
        [&](const Eigen::VectorXd& v) -> Eigen::Vector2d { return predict(v).value; }, x0, i);
    EXPECT_LT((fd - p0.jacobian.col(i)).cwiseAbs().maxCoeff(), 3e-4) << "state " << i;
  }
  // The bounce and the calibration's pitch, roll and height move the point
  // alike; the focal column is its own.
  EXPECT_EQ(p0.jacobian.middleCols<3>(6), p0.jacobian.middleCols<3>(9));
  EXPECT_GT(p0.jacobian.col(12).norm(), 0.1);
  // Away from zero the bounce's and the calibration's columns are still
  // exact (the prediction is linear in them), and the grid's miss only
  // their Jacobian's own change with the grid, held at the prediction:
  // 4 mrad of pitch on a slope of the bounce Jacobian of about 2y/h_c.
  const Eigen::VectorXd x1 =
      StateWith(Eigen::Vector3d(0.004, -0.003, 0.005), Eigen::Vector4d(0.002, -0.004, 0.006, 0.01));
  const Prediction p1 = predict(x1);
  for (int i = 0; i < 16; ++i) {
    const Eigen::Vector2d fd = CentralDifference(
        [&](const Eigen::VectorXd& v) -> Eigen::Vector2d { return predict(v).value; }, x1, i);
    const double tolerance = i >= 6 && i < 13 ? 1e-7 : 0.05 * p1.jacobian.col(i).norm() + 3e-4;
    EXPECT_LT((fd - p1.jacobian.col(i)).cwiseAbs().maxCoeff(), tolerance) << "state " << i;
  }
}

}  // namespace
}  // namespace plantscale::tracking
