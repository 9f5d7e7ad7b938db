#include "engine/rows/orientation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

namespace plantscale::rows {
namespace {

constexpr int kWidth = 128, kHeight = 96;
constexpr double kBottom = kHeight - 0.5;

// Rows u_n(v) = (s_c + n·d)(1 − g·Δv) + c·Δv drawn as lines of plant matter.
cv::Mat Rows(double g, double c, double sc, double d) {
  cv::Mat plant(kHeight, kWidth, CV_32FC1, cv::Scalar(0.0));
  for (int n = -6; n <= 6; ++n) {
    const auto at = [&](double dv) {
      const double u = (sc + n * d) * (1.0 - g * dv) + c * dv;
      return cv::Point(static_cast<int>(std::lround(u * 16)),
                       static_cast<int>(std::lround((kBottom - dv) * 16)));
    };
    const double top = g > 0.0 ? std::min(0.8 / g, kBottom) : kBottom;
    cv::line(plant, at(0.0), at(top), cv::Scalar(1.0), 2, cv::LINE_AA, 4);
  }
  return plant;
}

TEST(OrientationFieldTest, ConvergingRowsSupportTheirOwnVanishingPointMost) {
  const double g = 1.0 / 150.0, c = 0.5;  // vanishing point 150 px above the bottom
  OrientationField field;
  field.Build(Rows(g, c, 64.0, 30.0), 1.0, 1.0, kBottom);
  ASSERT_GT(field.cells(), 100u);
  const double own = field.Support(g, c);
  // Streaks along their lines: sin^16 near 1 on most cells, minus chance.
  EXPECT_GT(own, 0.5);  // measured 0.76
  // Another vanishing point (measured 0.08, 0.55, and 0.27 for parallel rows): half as high, or 20
  // px to the side.
  EXPECT_LT(field.Support(2.0 * g, 2.0 * c), 0.6 * own);
  EXPECT_LT(field.Support(g, c + 20.0 * g), 0.8 * own);
  // Parallel vertical rows would be a poor fit.
  EXPECT_LT(field.Support(0.0, 0.0), 0.6 * own);
}

TEST(OrientationFieldTest, ParallelLeaningRowsSupportTheirLean) {
  OrientationField field;
  field.Build(Rows(0.0, 0.3, 40.0, 25.0), 1.0, 1.0, kBottom);
  const double own = field.Support(0.0, 0.3);
  EXPECT_GT(own, 0.5);  // measured 0.79
  // 0.3 of lean either side: measured 0.34 and 0.38.
  EXPECT_LT(field.Support(0.0, 0.0), 0.6 * own);
  EXPECT_LT(field.Support(0.0, 0.6), 0.6 * own);
}

TEST(OrientationFieldTest, ScatteredRoundBlobsSupportNothingBeyondChance) {
  cv::Mat plant(kHeight, kWidth, CV_32FC1, cv::Scalar(0.0));
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> x(0, kWidth - 1), y(0, kHeight - 1);
  for (int i = 0; i < 60; ++i) cv::circle(plant, {x(rng), y(rng)}, 3, cv::Scalar(1.0), cv::FILLED);
  OrientationField field;
  field.Build(plant, 1.0, 1.0, kBottom);
  for (const double g : {0.0, 1.0 / 150.0}) {
    for (const double c : {-0.5, 0.0, 0.5}) EXPECT_LT(field.Support(g, c), 0.1) << g << " " << c;
  }
}

TEST(OrientationFieldTest, BlankImageHasNoCellsAndNoSupport) {
  OrientationField field;
  field.Build(cv::Mat(kHeight, kWidth, CV_32FC1, cv::Scalar(0.0)), 1.0, 1.0, kBottom);
  EXPECT_EQ(field.cells(), 0u);
  EXPECT_EQ(field.Support(0.01, 0.2), 0.0);
}

TEST(OrientationFieldTest, ChanceIsTheMeanOfSinToTheSixteenth) {
  double sum = 0.0;
  constexpr int kSteps = 100000;
  for (int i = 0; i < kSteps; ++i) sum += std::pow(std::sin(M_PI * (i + 0.5) / kSteps), 16);
  EXPECT_NEAR(sum / kSteps, OrientationField::kChance, 1e-9);
}

}  // namespace
}  // namespace plantscale::rows
