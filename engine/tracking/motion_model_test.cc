#include "engine/tracking/motion_model.h"

#include <gtest/gtest.h>

#include <cmath>


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

}  // namespace
}  // namespace plantscale::tracking
