#include "evaluation/row_fit.h"

#include <gtest/gtest.h>

#include <random>

namespace plantscale::motion {
namespace {

TEST(RowFit, ALineThroughExactPointsHasNoResidual) {
  std::vector<Eigen::Vector2d> p;
  for (int i = 0; i < 5; ++i) p.emplace_back(0.1 + 0.01 * i, 0.3 * i);
  const FittedLine line = FitLine(p);
  EXPECT_NEAR(line.rms_m, 0.0, 1e-12);
  EXPECT_NEAR(line.direction.x() / line.direction.y(), 0.01 / 0.3, 1e-12);
  EXPECT_NEAR(line.XAt(0.6), 0.12, 1e-12);
}

// Three rows 0.4 m apart, plants every 0.3 m with 5 mm scatter: the RMS,
// angle and spacing the paper's table reports come back.
TEST(RowFit, ThreeRowsGiveTheirScatterAngleAndSpacing) {
  std::mt19937 rng(2);
  std::normal_distribution<double> scatter(0.0, 0.005);
  std::vector<Eigen::Vector2d> plants;
  for (int row = -1; row <= 1; ++row) {
    for (int k = 0; k < 25; ++k) plants.emplace_back(0.4 * row + scatter(rng), 0.3 * k + scatter(rng));
  }
  const RowFit fit = FitRows(plants, 3.6, RowFitOptions{});
  ASSERT_EQ(fit.rows.size(), 3U);
  EXPECT_NEAR(fit.mean_rms_m, 0.005, 0.0015);
  EXPECT_LT(fit.mean_angle_rad * 180.0 / M_PI, 0.2);
  ASSERT_EQ(fit.spacings_m.size(), 2U);
  EXPECT_NEAR(fit.mean_spacing_m, 0.4, 0.004);
}

TEST(RowFit, APlantFarFromItsRowIsLeftOutOfTheFit) {
  std::vector<Eigen::Vector2d> plants;
  for (int k = 0; k < 10; ++k) plants.emplace_back(0.002 * (k % 2), 0.3 * k);
  plants.emplace_back(0.1, 1.35);  // a weed blob taken for crop, 10 cm off the row
  const RowFit fit = FitRows(plants, 1.35, RowFitOptions{});
  ASSERT_EQ(fit.rows.size(), 1U);
  EXPECT_EQ(fit.rows[0].outliers, 1);
  EXPECT_NEAR(fit.rows[0].rms_m, 0.001, 1e-4);  // the ±1 mm scatter of the others
  RowFitOptions keep_all;
  keep_all.outlier_m = 0.0;
  EXPECT_GT(FitRows(plants, 1.35, keep_all).rows[0].rms_m, 0.02);
}

TEST(RowFit, RowsWithTooFewPlantsAreNotFitted) {
  const std::vector<Eigen::Vector2d> plants{{0, 0}, {0, 1}, {0.4, 0}, {0.4, 0.5}, {0.4, 1}};
  const RowFit fit = FitRows(plants, 0.5, RowFitOptions{});
  ASSERT_EQ(fit.rows.size(), 1U);
  EXPECT_NEAR(fit.rows[0].point_m.x(), 0.4, 1e-12);
  EXPECT_EQ(fit.mean_spacing_m, 0.0);
}

}  // namespace
}  // namespace plantscale::motion
