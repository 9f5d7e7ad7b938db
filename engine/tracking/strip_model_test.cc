#include "engine/tracking/strip_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "engine/tracking/observation_test_fixture.h"

namespace plantscale::tracking {
namespace {

using geometry::GridState;
using testing::CentralDifference;
using testing::FieldObservation;

// A strip of three plants touching along row +1 (TrackerOptions::
// merged_row_strips): its lateral position normalᵀ·mean(predictions), the
// normal held at the prediction, against ∂/∂ every state; the plants carry
// their own offsets and heights.
TEST(StripModel, StripAcrossItsRowMatchesFiniteDifferences) {
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
