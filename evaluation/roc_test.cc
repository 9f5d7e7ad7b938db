#include "evaluation/roc.h"

#include <gtest/gtest.h>

#include "engine/common/rng.h"

namespace plantscale::vision {
namespace {

// AUC equals the Wilcoxon statistic of eqs. 2.9–2.10 computed pair by pair.
TEST(Roc, AucEqualsWilcoxonStatistic) {
  Rng rng(11);
  std::vector<int> plant, soil;
  RocAccumulator acc(0.0, 256.0, 256);
  for (int i = 0; i < 400; ++i) {
    plant.push_back(std::clamp(static_cast<int>(rng.Normal(150.0, 30.0)), 0, 255));
    acc.Add(plant.back(), true);
  }
  for (int i = 0; i < 700; ++i) {
    soil.push_back(std::clamp(static_cast<int>(rng.Normal(100.0, 30.0)), 0, 255));
    acc.Add(soil.back(), false);
  }
  double w = 0.0;
  for (int p : plant) {
    for (int n : soil) w += p > n ? 1.0 : (p == n ? 0.5 : 0.0);
  }
  w /= static_cast<double>(plant.size() * soil.size());
  const RocCurve curve = acc.Curve();
  EXPECT_NEAR(curve.Auc(), w, 1e-12);
  EXPECT_EQ(curve.positives, 400u);
  EXPECT_NEAR(curve.points.front().tpr, 1.0, 1e-12);
  EXPECT_NEAR(curve.points.back().fpr, 0.0, 1e-12);
}

// The costs-ratio operating point minimises Φ·FP − TP (eq. 2.16 with 2.23).
TEST(Roc, OperatingPointMinimisesBayesRisk) {
  Rng rng(3);
  RocAccumulator acc(0.0, 256.0, 256);
  for (int i = 0; i < 3000; ++i) acc.Add(rng.Normal(140.0, 25.0), true);
  for (int i = 0; i < 9000; ++i) acc.Add(rng.Normal(90.0, 20.0), false);
  const RocCurve curve = acc.Curve();
  for (double phi : {0.3, 1.0, 3.644}) {
    const RocPoint op = curve.OperatingPoint(phi);
    for (const RocPoint& p : curve.points) {
      EXPECT_LE(phi * op.fp - op.tp, phi * p.fp - p.tp + 1e-9);
    }
  }
  // A larger Φ favours soil: the threshold rises.
  EXPECT_GT(curve.OperatingPoint(3.644).threshold, curve.OperatingPoint(0.3).threshold);
}

TEST(Roc, DoubtBandIsOnePixelEachSideOfTheBorder) {
  cv::Mat labels(20, 20, CV_8UC1, cv::Scalar(0));
  labels(cv::Rect(5, 5, 10, 10)).setTo(1);
  cv::Mat doubt;
  DoubtBand(labels, 1, doubt);
  // Ring 12×12 outside minus 8×8 inside.
  EXPECT_EQ(cv::countNonZero(doubt), 12 * 12 - 8 * 8);
  EXPECT_EQ(doubt.at<uint8_t>(10, 10), 0);
  EXPECT_EQ(doubt.at<uint8_t>(5, 5), 255);
  EXPECT_EQ(doubt.at<uint8_t>(4, 4), 255);
  EXPECT_EQ(doubt.at<uint8_t>(3, 3), 0);
}

}  // namespace
}  // namespace plantscale::vision
