#include "engine/rows/row_detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "engine/rows/label_lines.h"

namespace plantscale::rows {
namespace {

// A synthetic plant mask of crop rows u_n(v) = (sc + n d)(1 − gΔv) + cΔv:
// plants along each row, smaller and closer together towards the vanishing
// point, a fraction missing, plus weeds scattered between the rows.
struct Scene {
  int width = 640, height = 480;
  double sc = 300.0, d = 180.0, g = 0.0, c = 0.0;
  int n_min = -3, n_max = 3;
  double plant_radius = 0.12;  // of the local row spacing
  double missing = 0.2;
  int weeds = 0;
  double weed_radius_px = 4.0;
  double top_v = 0.0;  // no plants above this
  double step = 0.25;     // between plants along a row, of the local row spacing
  double jitter = 0.0;    // sd of a plant's place across its row, of the local row spacing

  double Shrink(double v) const { return 1.0 - g * (height - 0.5 - v); }
  double U(int n, double v) const {
    return (sc + n * d) * Shrink(v) + c * (height - 0.5 - v);
  }
  cv::Mat Draw(uint32_t seed) const {
    cv::Mat mask(height, width, CV_8UC1, cv::Scalar(0));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> across(0.0, jitter);
    for (int n = n_min; n <= n_max; ++n) {
      for (double v = height - 0.5 + 0.3 * d * unit(rng); v > top_v;) {
        const double s = Shrink(v);
        if (s * d < 4.0) break;
        if (unit(rng) >= missing) {
          const int r = std::max(1, static_cast<int>(std::lround(plant_radius * d * s)));
          const double u = U(n, v) + (jitter > 0.0 ? across(rng) * d * s * s : 0.0);
          cv::circle(mask, cv::Point(static_cast<int>(u), static_cast<int>(v)), r, cv::Scalar(255),
                     cv::FILLED);
        }
        v -= step * d * s;
      }
    }
    for (int k = 0; k < weeds; ++k) {
      const int r = std::max(1, static_cast<int>(std::lround(weed_radius_px * (0.5 + unit(rng)))));
      cv::circle(mask, cv::Point(static_cast<int>(unit(rng) * width), static_cast<int>(top_v + unit(rng) * (height - top_v))),
                 r, cv::Scalar(255), cv::FILLED);
    }
    return mask;
  }
};

// Largest |u − u_true| over the detected rows at image height v, in units
// of the true local spacing; rows are matched by their position.
double WorstError(const RowDetection& det, const Scene& scene, double v) {
  double worst = 0.0;
  for (const DetectedRow& row : det.rows) {
    const double u = det.U(row.n, v);
    double best = 1e9;
    for (int n = scene.n_min; n <= scene.n_max; ++n) best = std::min(best, std::abs(u - scene.U(n, v)));
    worst = std::max(worst, best / (scene.d * scene.Shrink(v)));
  }
  return worst;
}

TEST(RowDetectorTest, ConvergingRowsGiveVanishingPointSpacingAndRows) {
  Scene scene;
  scene.g = 1.0 / 520.0;  // vanishing point 520 px above the bottom row
  scene.c = scene.g * 350.0;  // ... at u = 350
  scene.weeds = 60;
  scene.top_v = 40.0;
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(scene.Draw(1));
  ASSERT_GT(det.confidence, 0.3) << det.reason;
  EXPECT_NEAR(det.spacing_px, 180.0, 180.0 * 0.03);
  const auto vp = det.VanishingPoint();
  ASSERT_TRUE(vp.has_value());
  EXPECT_NEAR(vp->x(), 350.0, 25.0);
  EXPECT_NEAR(vp->y(), 479.5 - 520.0, 30.0);
  EXPECT_NEAR(det.CentralOffsetPx(), 300.0 - 320.0, 5.0);
  // Rows n = −1, 0, 1 cross the bottom in the image; −2 and 2 enter from the sides.
  EXPECT_GE(det.rows.size(), 5U);
  EXPECT_LT(WorstError(det, scene, 479.5), 0.05);
  EXPECT_LT(WorstError(det, scene, 240.0), 0.05);
  EXPECT_LT(det.top_v_px, 200.0);
}

TEST(RowDetectorTest, ParallelLeaningRowsFromAboveWithWeeds) {
  Scene scene;
  scene.width = 320;
  scene.height = 240;
  scene.sc = 150.0;
  scene.d = 64.0;
  scene.c = 0.25;  // rows lean right going up
  scene.n_min = -6;
  scene.n_max = 6;
  scene.weeds = 40;
  scene.weed_radius_px = 2.0;
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(scene.Draw(2));
  ASSERT_GT(det.confidence, 0.3) << det.reason;
  EXPECT_NEAR(det.spacing_px, 64.0, 64.0 * 0.03);
  EXPECT_LT(std::abs(det.convergence) * 240.0, 0.05);  // parallel
  EXPECT_NEAR(det.lean, 0.25, 0.02);
  EXPECT_LT(WorstError(det, scene, 239.5), 0.05);
  EXPECT_LT(WorstError(det, scene, 10.0), 0.05);
  EXPECT_GE(det.rows.size(), 5U);
}

TEST(RowDetectorTest, RowsAreNumberedLeftToRightAndCentralIsNearestTheMiddle) {
  Scene scene;
  scene.g = 1.0 / 700.0;
  scene.c = scene.g * 200.0;
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(scene.Draw(3));
  ASSERT_GT(det.confidence, 0.3) << det.reason;
  for (size_t i = 1; i < det.rows.size(); ++i) {
    EXPECT_EQ(det.rows[i].n, det.rows[i - 1].n + 1);
    EXPECT_GT(det.rows[i].bottom_u_px, det.rows[i - 1].bottom_u_px);
  }
  EXPECT_NEAR(det.U(0, 479.5), 300.0, 5.0);  // the row at 300 is nearest u = 320
}

TEST(RowDetectorTest, WideRowsThatNearlyTouchAreCentredByTheirGaps) {
  Scene scene;
  scene.g = 1.0 / 520.0;
  scene.c = scene.g * 330.0;
  scene.plant_radius = 0.42;  // rows 84 % of their spacing wide
  scene.missing = 0.1;
  scene.n_min = -1;
  scene.n_max = 1;  // one bed of three rows on bare soil
  scene.top_v = 60.0;
  // The straight model's refit centres rows by their gaps; the curve fit
  // (issue 34), a cosine comb, moves these outer rows by 0.1–0.17 of a
  // spacing (docs/results/2026-11-27-rows-curves.md, left to do), so this is the
  // straight model's property alone.
  RowDetectorOptions options;
  options.curves = false;
  RowDetector detector{options};
  const RowDetection det = detector.Detect(scene.Draw(4));
  ASSERT_GT(det.confidence, 0.0) << det.reason;
  EXPECT_EQ(det.rows.size(), 3U);
  EXPECT_NEAR(det.spacing_px, 180.0, 180.0 * 0.04);
  EXPECT_LT(WorstError(det, scene, 479.5), 0.06);
  EXPECT_LT(WorstError(det, scene, 200.0), 0.06);
}

TEST(RowDetectorTest, ARowWithMorePlantsMissingThanPresentIsStillARow) {
  // Outer rows full, the central row with 60 % of its plants missing: the
  // comb of twice the spacing through the outer rows must not win.
  Scene outer;
  outer.g = 1.0 / 600.0;
  outer.c = outer.g * 320.0;
  outer.n_min = -1;
  outer.n_max = 1;
  outer.missing = 0.05;
  Scene centre = outer;
  centre.n_min = 0;
  centre.n_max = 0;
  centre.missing = 0.6;
  Scene sides = outer;
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8UC1);
  for (int n : {-1, 1}) {
    sides.n_min = sides.n_max = n;
    cv::bitwise_or(mask, sides.Draw(static_cast<uint32_t>(5 + n)), mask);
  }
  cv::bitwise_or(mask, centre.Draw(9), mask);
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(mask);
  ASSERT_GT(det.confidence, 0.0) << det.reason;
  EXPECT_NEAR(det.spacing_px, 180.0, 180.0 * 0.04);
  EXPECT_EQ(det.rows.size(), 3U);
  EXPECT_LT(WorstError(det, outer, 479.5), 0.05);
}

// A low-tilt view like a grower's photograph (dev image 0's geometry): the
// vanishing point just above the image, two rows crossing the bottom and
// the outer rows fanning out through the image's sides; optionally,
// towards the horizon, the rows merged into one canopy (blobs as wide as
// the rows are apart), whose bands a vanishing point placed too low drops.
cv::Mat LowTiltField(const Scene& scene, double canopy_bottom_v, uint32_t seed) {
  cv::Mat mask = scene.Draw(seed);
  std::mt19937 rng(seed + 100);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < 400 && canopy_bottom_v > 0.0; ++k) {
    const double v = unit(rng) * canopy_bottom_v;
    const double r = 0.3 * scene.d * scene.Shrink(v);
    cv::circle(mask, cv::Point(static_cast<int>(unit(rng) * scene.width), static_cast<int>(v)),
               std::max(1, static_cast<int>(r)), cv::Scalar(255), cv::FILLED);
  }
  return mask;
}

Scene LowTiltScene() {
  Scene scene;
  scene.width = 512;
  scene.height = 512;
  scene.g = 1.0 / 670.0;      // vanishing point 158 px above the image's top
  scene.c = scene.g * 276.0;  // ... at u = 276
  scene.sc = 290.0;
  scene.d = 227.0;            // rows 227 px apart at the bottom: 2 cross it
  scene.n_min = -5;
  scene.n_max = 4;
  scene.plant_radius = 0.15;
  scene.missing = 0.1;
  return scene;
}

TEST(RowDetectorTest, LowTiltFanOutFindsTheRowsEnteringThroughTheSides) {
  const Scene scene = LowTiltScene();
  RowDetector detector{RowDetectorOptions{}};
  int good = 0;
  for (uint32_t seed = 30; seed < 34; ++seed) {
    // Half the seeds with a canopy over the top 60 px where the rows merge.
    const double canopy = seed % 2 == 0 ? 60.0 : 0.0;
    const RowDetection det = detector.Detect(LowTiltField(scene, canopy, seed));
    ASSERT_GT(det.confidence, 0.0) << det.reason;
    // Tolerances: spacing within 5 %, every row within 8 % of the local
    // spacing at the bottom and half-way up, at least 4 rows (2 cross the
    // bottom, the others enter through the sides).
    const bool ok = std::abs(det.spacing_px - scene.d) < 0.05 * scene.d &&
                    WorstError(det, scene, 511.5) < 0.08 && WorstError(det, scene, 256.0) < 0.08 &&
                    det.rows.size() >= 4U;
    if (ok) ++good;
    EXPECT_TRUE(ok) << "seed " << seed << ": spacing " << det.spacing_px << ", rows "
                    << det.rows.size() << ", error " << WorstError(det, scene, 511.5) << " / "
                    << WorstError(det, scene, 256.0);
  }
  EXPECT_EQ(good, 4);
}

TEST(RowDetectorTest, ARowWithThreeQuartersOfItsPlantsMissingIsNotSkipped) {
  // The low-tilt field with the central row 75 % missing: the comb of twice
  // the spacing through the full rows on either side must not win.
  Scene full = LowTiltScene();
  Scene sparse = full;
  sparse.n_min = sparse.n_max = 0;
  sparse.missing = 0.75;
  RowDetector detector{RowDetectorOptions{}};
  int good = 0;
  for (uint32_t seed = 40; seed < 44; ++seed) {
    cv::Mat mask = cv::Mat::zeros(full.height, full.width, CV_8UC1);
    for (int n = full.n_min; n <= full.n_max; ++n) {
      if (n == 0) continue;
      Scene one = full;
      one.n_min = one.n_max = n;
      cv::bitwise_or(mask, one.Draw(seed * 16 + static_cast<uint32_t>(n + 8)), mask);
    }
    cv::bitwise_or(mask, sparse.Draw(seed), mask);
    const RowDetection det = detector.Detect(mask);
    ASSERT_GT(det.confidence, 0.0) << det.reason;
    // Tolerances: spacing within 5 % (twice the spacing is 100 % off), the
    // sparse row found within 8 % of the spacing at the bottom.
    const bool spacing_ok = std::abs(det.spacing_px - full.d) < 0.05 * full.d;
    bool sparse_found = false;
    for (const DetectedRow& row : det.rows) {
      if (std::abs(det.U(row.n, 511.5) - full.U(0, 511.5)) < 0.08 * full.d) sparse_found = true;
    }
    if (spacing_ok && sparse_found) ++good;
    EXPECT_TRUE(spacing_ok && sparse_found)
        << "seed " << seed << ": spacing " << det.spacing_px << ", rows " << det.rows.size();
  }
  EXPECT_EQ(good, 4);
}

TEST(RowDetectorTest, NoPlantMatterGivesNoRows) {
  RowDetector detector{RowDetectorOptions{}};
  const RowDetection det = detector.Detect(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)));
  EXPECT_EQ(det.confidence, 0.0);
  EXPECT_TRUE(det.rows.empty());
  EXPECT_NE(det.reason.find("no plant matter"), std::string::npos) << det.reason;
}

TEST(RowDetectorTest, ScatteredBlobsAreNotRows) {
  RowDetector detector{RowDetectorOptions{}};
  int with_rows = 0;
  for (uint32_t seed = 10; seed < 20; ++seed) {
    Scene scene;
    scene.n_min = 1;
    scene.n_max = 0;  // no rows at all
    scene.weeds = 150;
    scene.weed_radius_px = 8.0;
    const RowDetection det = detector.Detect(scene.Draw(seed));
    if (det.confidence > 0.0) ++with_rows;
    EXPECT_EQ(det.rows.empty(), det.confidence == 0.0);
  }
  EXPECT_EQ(with_rows, 0);
}

// A camera looking far along the bed (CRDLD test photographs 108-124): the
// vanishing point just above the image, rows two-fifths of the image apart
// at the bottom and fanning out to the sides, weeds everywhere. Few rows
// cross each band of the near field, so the bands' comb phases agree less
// than the 0.85 asked of plant matter in general; the streaks all pointing
// at the vanishing point confirm the rows (scattered blobs above have none).
TEST(RowDetectorTest, SharplyConvergingRowsAreConfirmedByTheirStreaks) {
  Scene scene;
  scene.width = 512;
  scene.height = 512;
  scene.g = 1.0 / 530.0;
  scene.c = scene.g * 270.0;
  scene.sc = 270.0;
  scene.d = 210.0;
  scene.n_min = -7;
  scene.n_max = 7;
  scene.plant_radius = 0.1;
  scene.step = 0.1;    // plants merge into streaks in the distance ...
  scene.jitter = 0.3;  // ... and stand anywhere about their row near the camera
  scene.missing = 0.5;
  scene.weeds = 100;
  scene.weed_radius_px = 6.0;
  RowDetector detector{RowDetectorOptions{}};
  RowDetectorOptions without_streaks;  // the straight model alone, ...
  without_streaks.curves = false;
  without_streaks.min_streak_support = 1.0;  // ... whose streaks never confirm
  RowDetector plain{without_streaks};
  int below_general_alignment = 0;
  for (uint32_t seed = 30; seed < 36; ++seed) {
    SCOPED_TRACE(seed);
    const cv::Mat mask = scene.Draw(seed);
    const RowDetection det = detector.Detect(mask);
    ASSERT_GT(det.confidence, 0.0) << det.reason;
    EXPECT_GE(det.streak_support, RowDetectorOptions{}.min_streak_support);
    EXPECT_NEAR(det.spacing_px, 210.0, 210.0 * 0.1);
    EXPECT_LT(WorstError(det, scene, 200.0), 0.15);
    if (det.alignment < 0.85) {
      ++below_general_alignment;
      EXPECT_EQ(plain.Detect(mask).confidence, 0.0);
    }
  }
  EXPECT_GE(below_general_alignment, 3);
}

TEST(RowDetectorTest, RejectsEmptyAndWrongTypeImages) {
  RowDetector detector{RowDetectorOptions{}};
  EXPECT_THROW(detector.Detect(cv::Mat()), DataError);
  EXPECT_THROW(detector.Detect(cv::Mat(10, 10, CV_8UC3, cv::Scalar(0, 0, 0))), DataError);
}

TEST(RowDetectorTest, InvalidOptionsAreNamed) {
  RowDetectorOptions o;
  o.strips = 1;
  o.max_spacing_fraction = 0.01;
  const OptionErrors e = o.Validate();
  ASSERT_EQ(e.size(), 2U);
  EXPECT_EQ(e[0].key, "strips");
  EXPECT_EQ(e[1].key, "max_spacing_fraction");
}

TEST(LabelLines, CentresOfTheWhiteRunsScaled) {
  const uint8_t row[10] = {0, 255, 255, 0, 127, 128, 0, 0, 200, 200};
  const std::vector<double> c = LabelLineCentres(row, 10);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_DOUBLE_EQ(c[0], 2.0);  // pixels 1..2: (1 + 3) / 2
  EXPECT_DOUBLE_EQ(c[1], 5.5);  // 127 is black, 128 white
  EXPECT_DOUBLE_EQ(c[2], 9.0);  // a run reaching the end
  EXPECT_DOUBLE_EQ(LabelLineCentres(row, 10, 2.0)[1], 11.0);
}

}  // namespace
}  // namespace plantscale::rows
