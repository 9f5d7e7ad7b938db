#include "evaluation/mrroc.h"

#include <gtest/gtest.h>

#include <vector>

namespace plantscale::classify {
namespace {

MrrocPoint Point(double fpr, double tpr) {
  MrrocPoint p;
  p.fpr = fpr;
  p.tpr = tpr;
  return p;
}

TEST(Mrroc, HullDropsPointsUnderIt) {
  const std::vector<MrrocPoint> hull =
      UpperHull({Point(0.1, 0.8), Point(0.2, 0.85), Point(0.3, 0.95), Point(0.5, 0.9)});
  // (0.2, 0.85) lies under the segment (0.1, 0.8)–(0.3, 0.95) at 0.875.
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_DOUBLE_EQ(hull[0].fpr, 0.0);
  EXPECT_DOUBLE_EQ(hull[1].fpr, 0.1);
  EXPECT_DOUBLE_EQ(hull[2].fpr, 0.3);
  EXPECT_DOUBLE_EQ(hull[3].fpr, 1.0);
}

TEST(Mrroc, SweepAucAndOperatingPoints) {
  // Crops are big and associate; weeds are small, and one weed sits on a crop.
  const std::vector<ClassifierSample> samples = {
      {0.02, false, 1.0, 100, 0},  {0.015, false, 2.0, 80, 0}, {0.002, false, 1.5, 20, 0},
      {0.002, false, 30.0, 0, 10}, {0.010, false, 40.0, 0, 10}, {0.002, false, 1.0, 0, 10},
  };
  const std::vector<double> areas = {0.0, 0.0025, 0.005};
  const std::vector<double> gates = {4.0, 100.0};
  const Mrroc r = SweepClassifier(samples, areas, gates);
  EXPECT_DOUBLE_EQ(r.positives, 200.0);
  EXPECT_DOUBLE_EQ(r.negatives, 30.0);
  ASSERT_EQ(r.classifiers.size(), 6u);
  // ς = 0.0025, χ² = 4: both big crops (180 of 200), no weed.
  const MrrocPoint& best = r.classifiers[2];
  EXPECT_NEAR(best.tpr, 0.9, 1e-12);
  EXPECT_NEAR(best.fpr, 0.0, 1e-12);
  // ς = 0, χ² = 4: every crop, and the weed on a crop (10 of 30).
  EXPECT_NEAR(r.classifiers[0].tpr, 1.0, 1e-12);
  EXPECT_NEAR(r.classifiers[0].fpr, 1.0 / 3.0, 1e-12);
  // Hull (0,0) (0,0.9) (1/3,1) (1,1): area 0.9·1/3·... by trapezia.
  const double auc = (1.0 / 3.0) * 0.5 * (0.9 + 1.0) + (2.0 / 3.0) * 1.0;
  EXPECT_NEAR(r.Auc(), auc, 1e-12);
  EXPECT_NEAR(r.NearestToCorner().tpr, 0.9, 1e-12);
  // Missing a crop pixel costs as much as spraying 1/Φ weed pixels; risk is
  // Φ·N·FPR − P·TPR: at Φ = 1, (0, 0.9) → −180, (1/3, 1) → 10 − 200 = −190.
  EXPECT_NEAR(r.OperatingPoint(1.0).tpr, 1.0, 1e-12);
  // At Φ = 3 spraying a weed pixel is dearer: (1/3, 1) → 30 − 200 = −170.
  EXPECT_NEAR(r.OperatingPoint(3.0).tpr, 0.9, 1e-12);
  EXPECT_THROW(r.OperatingPoint(0.0), std::invalid_argument);
}

// Two touching plants along a row make one blob whose centroid lies between
// them; split among the predictions, each half is a crop plant again.

}  // namespace
}  // namespace plantscale::classify
