#include "engine/rows/curve_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "engine/rows/row_detector.h"

namespace plantscale::rows {
namespace {

// A plant mask of rows that bend: u_n(v) = c(v) + n·d(v), c quadratic in
// the height above the bottom (`bend` px at the top), d shrinking linearly
// towards the top (to `top_spacing` of the bottom's); plants along each
// row, a fraction missing, weeds between the rows.
struct CurvedScene {
  int width = 320, height = 240;
  double c0 = 150.0, bend = 60.0, d0 = 70.0, top_spacing = 0.5;
  int n_min = -4, n_max = 4;
  double missing = 0.2;
  int weeds = 40;

  double T(double v) const { return (height - 0.5 - v) / height; }
  double C(double v) const { return c0 + bend * T(v) * T(v); }
  double D(double v) const { return d0 * (1.0 - (1.0 - top_spacing) * T(v)); }
  double U(int n, double v) const { return C(v) + n * D(v); }
  cv::Mat Draw(uint32_t seed) const {
    cv::Mat mask(height, width, CV_8UC1, cv::Scalar(0));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int n = n_min; n <= n_max; ++n) {
      for (double v = height - 0.5 - 10.0 * unit(rng); v > 0.0;) {
        const double d = D(v);
        if (unit(rng) >= missing) {
          const int r = std::max(1, static_cast<int>(std::lround(0.12 * d)));
          cv::circle(mask, cv::Point(static_cast<int>(U(n, v)), static_cast<int>(v)), r,
                     cv::Scalar(255), cv::FILLED);
        }
        v -= 0.35 * d;
      }
    }
    for (int i = 0; i < weeds; ++i) {
      cv::circle(mask, cv::Point(static_cast<int>(unit(rng) * width), static_cast<int>(unit(rng) * height)),
                 2, cv::Scalar(255), cv::FILLED);
    }
    return mask;
  }
};

// The mean CRDA-style score of the detection against the scene's three
// central rows (matched by the detected row nearest the true central row
// at the bottom), over the image rows from the bottom up to `top_fraction`
// of the height, and the worst error in spacings.
struct Agreement {
  double score = 0.0;
  double worst = 0.0;
};
Agreement Compare(const RowDetection& det, const CurvedScene& scene, double top_fraction) {
  Agreement a;
  if (det.rows.empty()) return a;
  const double vb = scene.height - 0.5;
  int central = det.rows.front().n;
  for (const DetectedRow& r : det.rows) {
    if (std::abs(det.U(r.n, vb) - scene.U(0, vb)) < std::abs(det.U(central, vb) - scene.U(0, vb))) {
      central = r.n;
    }
  }
  int count = 0;
  for (int vi = scene.height - 1; vi >= static_cast<int>((1.0 - top_fraction) * scene.height); --vi) {
    const double v = vi + 0.5;
    const double d = scene.D(v);
    for (int k = -1; k <= 1; ++k) {
      const double e = std::abs(det.U(central + k, v) - scene.U(k, v)) / d;
      a.worst = std::max(a.worst, e);
      a.score += std::max(0.0, 1.0 - (e / 0.1) * (e / 0.1));
      ++count;
    }
  }
  a.score /= count;
  return a;
}

TEST(CurveFitTest, FollowsRowsThatBend) {
  CurvedScene scene;
  RowDetector detector{RowDetectorOptions{}};
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    const RowDetection det = detector.Detect(scene.Draw(seed));
    ASSERT_GT(det.confidence, 0.0) << det.reason;
    ASSERT_FALSE(det.curve.empty());
    const Agreement a = Compare(det, scene, 0.9);
    // Rows bending by 60 px (almost a spacing) over the image: within a
    // tenth of a spacing (CRDA > 0) everywhere, and a mean score of 0.8.
    EXPECT_GT(a.score, 0.8) << "seed " << seed;
    EXPECT_LT(a.worst, 0.1) << "seed " << seed;
    // The straight model alone (without the curve and the centring) cannot follow them.
    RowDetectorOptions straight_options;
    straight_options.curves = false;
    straight_options.centring.enabled = false;
    RowDetector straight(straight_options);
    const RowDetection s = straight.Detect(scene.Draw(seed));
    EXPECT_LT(Compare(s, scene, 0.9).score, a.score - 0.1) << "seed " << seed;
  }
}

TEST(CurveFitTest, KeepsStraightRowsStraight) {
  CurvedScene scene;
  scene.bend = 0.0;
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(scene.Draw(7));
  ASSERT_GT(det.confidence, 0.0) << det.reason;
  const Agreement a = Compare(det, scene, 0.9);
  EXPECT_GT(a.score, 0.85);
  EXPECT_LT(a.worst, 0.1);
}

TEST(CurveFitTest, RowsLeavingTheImageSideContinuePastIt) {
  CurvedScene scene;
  scene.bend = 120.0;  // the central row leaves through the right side near the top
  scene.c0 = 200.0;
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(scene.Draw(11));
  ASSERT_GT(det.confidence, 0.0) << det.reason;
  // Some reported row is beyond the right side at the top.
  bool beyond = false;
  for (const DetectedRow& r : det.rows) beyond |= det.U(r.n, det.top_v_px) > scene.width;
  EXPECT_TRUE(beyond);
  EXPECT_GT(Compare(det, scene, 0.6).score, 0.7);
}

TEST(CurveFitTest, NoRowsInScatteredPlants) {
  CurvedScene scene;
  scene.n_min = 1;
  scene.n_max = 0;  // no rows
  scene.weeds = 300;
  RowDetector detector{RowDetectorOptions{}};
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    const RowDetection det = detector.Detect(scene.Draw(seed));
    EXPECT_EQ(det.confidence, 0.0) << "seed " << seed;
    EXPECT_TRUE(det.rows.empty());
    EXPECT_FALSE(det.reason.empty());
  }
}

TEST(CurveFitTest, TinyImageHasNoRowsOrSomeWithoutFailing) {
  cv::Mat mask(16, 16, CV_8UC1, cv::Scalar(0));
  for (int x = 2; x < 16; x += 5) mask.col(x).setTo(255);
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(mask);
  for (const DetectedRow& r : det.rows) EXPECT_TRUE(std::isfinite(det.U(r.n, 0.5)));
}

TEST(CurveFitTest, CurveInterpolatesAndContinuesBeyondItsKnots) {
  RowDetection det;
  det.width_px = 100;
  det.height_px = 100;
  det.curve = {{90.0, 50.0, 20.0, 1.0}, {50.0, 60.0, 10.0, 1.0}, {10.0, 80.0, 10.0, 1.0}};
  EXPECT_NEAR(det.U(0, 70.0), 55.0, 1e-9);
  EXPECT_NEAR(det.U(1, 70.0), 55.0 + 15.0, 1e-9);
  EXPECT_NEAR(det.SpacingAt(30.0), 10.0, 1e-9);
  EXPECT_NEAR(det.U(0, 99.5), 50.0 - 9.5 / 40.0 * 10.0, 1e-9);  // below the bottom knot
  EXPECT_NEAR(det.U(-1, 0.0), 85.0 - 10.0, 1e-9);               // above the top knot
}

TEST(CurveFitTest, OptionsAreValidated) {
  CurveFitOptions o;
  EXPECT_TRUE(o.Validate().empty());
  o.bands = 1;
  o.phase_steps = 4;
  o.max_phase_jump = 0;
  EXPECT_EQ(o.Validate().size(), 3U);
  RowDetectorOptions r;
  r.curve.bands = 1;
  EXPECT_THROW(RowDetector{r}, InvalidOptionsError);
}

}  // namespace
}  // namespace plantscale::rows
