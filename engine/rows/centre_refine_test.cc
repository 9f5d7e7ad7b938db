#include "engine/rows/centre_refine.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "engine/rows/row_detector.h"

namespace plantscale::rows {
namespace {

// Five rows seen from above (parallel, 80 px apart on a 400 × 300 image):
// the comb puts row n at 200 + 80 n, the plants of row n grow along
// 200 + 80 n + shift + offset[n] + bend[n]·t², t = (299.5 − v)/300.
struct Field {
  int width = 400, height = 300;
  double d = 80.0, shift = 0.0;
  std::array<double, 5> offset{}, bend{};
  int weeds = 40;

  double True(int n, double v) const {
    const double t = (height - 0.5 - v) / height;
    const size_t i = static_cast<size_t>(n + 2);
    return 200.0 + n * d + shift + offset[i] + bend[i] * t * t;
  }
  // The plant fraction (CV_32F) the detector refines on: plants of 7 px
  // radius every 12 px along each row, a fifth missing, weeds between.
  cv::Mat Draw(uint32_t seed) const {
    cv::Mat mask(height, width, CV_8UC1, cv::Scalar(0));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int n = -2; n <= 2; ++n) {
      for (double v = height - 4.0; v > 4.0; v -= 12.0) {
        if (unit(rng) < 0.2) continue;
        const double u = True(n, v) + 2.0 * (unit(rng) - 0.5);
        cv::circle(mask, cv::Point2d(u, v), 7, cv::Scalar(255), cv::FILLED);
      }
    }
    for (int k = 0; k < weeds; ++k) {
      cv::circle(mask, cv::Point2d(unit(rng) * width, unit(rng) * height), 3, cv::Scalar(255), cv::FILLED);
    }
    cv::Mat plant;
    mask.convertTo(plant, CV_32F, 1.0 / 255.0);
    return plant;
  }
  // The comb's detection: rows −2..2 at 200 + 80 n, parallel and upright.
  RowDetection Comb() const {
    RowDetection det;
    det.width_px = width;
    det.height_px = height;
    det.confidence = 0.8;
    det.centre_u_px = 200.0;
    det.spacing_px = d;
    for (int n = -2; n <= 2; ++n) det.rows.push_back({n, 200.0 + n * d, 1.0});
    return det;
  }
};

// The largest |refined u − true u| over the rows at heights across the
// image, in pixels.
double WorstCentringError(const Field& field, uint32_t seed, const CentreRefineOptions& o = {}) {
  RowDetection det = field.Comb();
  const cv::Mat plant = field.Draw(seed);
  det.centring = FitCentres(ObserveCentres(plant, 1.0, 1.0, det, o), det, o);
  EXPECT_FALSE(det.centring.empty());
  double worst = 0.0;
  for (const double v : {290.0, 220.0, 150.0, 80.0, 15.0}) {
    for (int n = -2; n <= 2; ++n) worst = std::max(worst, std::abs(det.U(n, v) - field.True(n, v)));
  }
  return worst;
}

TEST(CentreRefineTest, RowsOnTheCombStayOnIt) {
  const Field field;
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    EXPECT_LT(WorstCentringError(field, seed), 0.02 * field.d) << "seed " << seed;
  }
}

TEST(CentreRefineTest, CombOffItsRowsIsMovedOntoTheirPlants) {
  Field field;
  field.shift = 9.0;  // the whole comb 0.11 spacings left of the plants
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    EXPECT_LT(WorstCentringError(field, seed), 0.025 * field.d) << "seed " << seed;
  }
}

TEST(CentreRefineTest, EachRowIsMovedOntoItsOwnPlants) {
  Field field;
  field.offset = {7.0, -6.0, 0.0, 8.0, -5.0};  // uneven drill rows, up to 0.1 spacings
  field.bend = {0.0, 0.0, 12.0, 0.0, -10.0};  // two rows bending off the comb towards the top
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    EXPECT_LT(WorstCentringError(field, seed), 0.03 * field.d) << "seed " << seed;
  }
  // With the rows tied to the comb (per-row terms ridged away), only the
  // shared correction is left and the uneven rows stay off.
  CentreRefineOptions tied;
  tied.row_ridge = 1e6;
  EXPECT_GT(WorstCentringError(field, 1, tied), 0.06 * field.d);
}

TEST(CentreRefineTest, OffsetHoldsBeyondTheFittedHeights) {
  CentreRefinement r;
  r.shared_a = {0.1, 0.2};  // e = 0.1 + 0.2 s
  r.shared_b = {0.0, 0.0};
  r.v_bottom = 99.5;
  r.height = 100.0;
  r.t_max = 0.5;  // observations up to v = 49.5
  EXPECT_NEAR(r.Offset(0, 99.5), 0.1, 1e-12);
  EXPECT_NEAR(r.Offset(3, 74.5), 0.2, 1e-12);
  EXPECT_NEAR(r.Offset(0, 49.5), 0.3, 1e-12);
  EXPECT_NEAR(r.Offset(0, 0.0), 0.3, 1e-12);  // held above
  EXPECT_NEAR(r.Offset(0, 200.0), 0.1, 1e-12);  // and below
}

TEST(CentreRefineTest, InvalidOptionsAreNamed) {
  CentreRefineOptions o;
  o.window_fraction = 0.0;
  o.degree = 7;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 2U);
  EXPECT_EQ(e[0].key, "window_fraction");
  EXPECT_EQ(e[1].key, "degree");
}

}  // namespace
}  // namespace plantscale::rows
