#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "engine/classify/crop_classifier.h"
#include "engine/geometry/test_cameras.h"

namespace plantscale::classify {
namespace {

PredictedCrop CropAt(double x, double y) {
  PredictedCrop c;
  c.ground_m = {x, y};
  c.jacobian.setZero();
  c.jacobian(0, 0) = 1.0;  // t_x moves the plant across
  c.jacobian(1, 1) = 1.0;  // Y moves it along
  return c;
}

// A 40 cm² size filter and the 99 % gate with 1 cm centroid noise and no
// plant offset.
ClassifierOptions SizeAndGate() {
  ClassifierOptions o;
  o.min_crop_area_m2 = 0.004;
  o.assoc_chi2 = 9.21;
  o.feature_sd_m = 0.01;
  o.plant_sd_m = 0.0;
  return o;
}

tracking::Feature FeatureAt(double x, double y, double area_m2, bool clipped = false) {
  tracking::Feature f;
  f.ground_m = {x, y};
  f.area_m2 = area_m2;
  f.clipped = clipped;
  return f;
}

TEST(CropClassifier, AssociationCovarianceIsHPHtPlusGroundNoise) {
  ClassifierOptions o;
  o.feature_sd_m = 0.01;
  o.plant_sd_m = 0.02;
  geometry::Matrix5d p = geometry::Matrix5d::Zero();
  p(0, 0) = 0.03 * 0.03;
  p(1, 1) = 0.04 * 0.04;
  const Eigen::Matrix2d s = AssociationCovariance(CropAt(0, 1), p, o);
  EXPECT_NEAR(s(0, 0), 0.03 * 0.03 + 0.01 * 0.01 + 0.02 * 0.02, 1e-12);
  EXPECT_NEAR(s(1, 1), 0.04 * 0.04 + 0.01 * 0.01 + 0.02 * 0.02, 1e-12);
  EXPECT_NEAR(s(0, 1), 0.0, 1e-12);
}

TEST(CropClassifier, SizeFilterThenAssociation) {
  ClassifierOptions o = SizeAndGate();
  o.sure_crop_area_m2 = 0.03;
  CropClassifier classifier(o);
  const std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0), CropAt(0.475, 1.0)};
  const std::vector<tracking::Feature> features = {
      FeatureAt(0.01, 1.01, 0.02),         // big, near: crop
      FeatureAt(0.01, 1.01, 0.001),        // small, near: weed by size
      FeatureAt(0.2, 1.0, 0.02),           // big, between rows: weed by association
      FeatureAt(0.47, 0.99, 0.001, true),  // clipped (area cut) but associated: crop
  };
  std::vector<BlobDecision> d;
  classifier.Classify(features, crops, geometry::Matrix5d::Zero(), d);
  ASSERT_EQ(d.size(), 4u);
  EXPECT_TRUE(d[0].crop);
  EXPECT_NEAR(d[0].gamma2, (0.01 * 0.01 + 0.01 * 0.01) / 1e-4, 1e-9);
  EXPECT_NEAR(d[0].distance_m, std::sqrt(2.0) * 0.01, 1e-12);
  EXPECT_FALSE(d[1].crop);
  EXPECT_FALSE(d[2].crop);
  EXPECT_NEAR(d[2].distance_m, 0.2, 1e-12);
  EXPECT_TRUE(d[3].crop);
  EXPECT_EQ(d[3].n, 0);  // the second prediction (n defaults to 0 in CropAt)
  EXPECT_NEAR(d[3].distance_m, std::hypot(0.005, 0.01), 1e-12);
  // A blob bigger than any weed is crop wherever it lies (merged plants).
  const std::vector<tracking::Feature> merged = {FeatureAt(0.2, 1.0, 0.05)};
  classifier.Classify(merged, crops, geometry::Matrix5d::Zero(), d);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_TRUE(d[0].crop);
}

// Young crop: whole crops of 0.005 m² teach the filter 0.3 × 0.005 = 0.0015
// m², and a crop of 0.002 m² that the fixed 0.004 m² called weed is crop.
TEST(CropClassifier, SizeFilterFollowsTheCropsOwnSize) {
  ClassifierOptions o = SizeAndGate();
  o.lone_crop_fraction = 0.0;  // the filter alone
  CropClassifier classifier(o);
  const std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0), CropAt(0.475, 1.0)};
  std::vector<BlobDecision> d;
  const std::vector<tracking::Feature> small = {FeatureAt(0.0, 1.0, 0.002)};
  classifier.Classify(small, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_FALSE(d[0].crop);
  EXPECT_DOUBLE_EQ(d[0].size_filter_m2, 0.004);
  // 19 frames of two crops each, and ones the filter must not learn from:
  // a clipped crop, a big weed between the rows.
  for (int k = 0; k < 19; ++k) {
    const double a = 0.004 + 0.0001 * (k % 3);  // median 0.0041 ... until the last
    const std::vector<tracking::Feature> f = {
        FeatureAt(0.0, 1.0, a), FeatureAt(0.475, 1.0, 0.0060), FeatureAt(0.47, 1.0, 0.5, true),
        FeatureAt(0.2, 1.0, 0.02)};
    classifier.Classify(f, crops, geometry::Matrix5d::Zero(), d);
    EXPECT_FALSE(d[3].crop);
  }
  // 38 whole crops: 19 of 0.004–0.0042 and 19 of 0.006; median 0.006 (the
  // 20th of 38 sorted), so the filter is 0.3 × 0.006 = 0.0018.
  EXPECT_NEAR(classifier.size_filter_m2(), 0.0018, 1e-12);
  classifier.Classify(small, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_TRUE(d[0].crop);
  EXPECT_NEAR(d[0].size_filter_m2, 0.0018, 1e-12);
  // Big crops leave the fixed filter: it never rises above ς.
  for (int k = 0; k < 60; ++k) {
    classifier.Classify(std::vector<tracking::Feature>{FeatureAt(0.0, 1.0, 0.05)}, crops,
                        geometry::Matrix5d::Zero(), d);
  }
  EXPECT_DOUBLE_EQ(classifier.size_filter_m2(), 0.004);
  // Off: ς alone, however small the crops.
  o.crop_size_fraction = 0.0;
  CropClassifier fixed(o);
  for (int k = 0; k < 60; ++k) {
    fixed.Classify(std::vector<tracking::Feature>{FeatureAt(0.0, 1.0, 0.0045)}, crops,
                   geometry::Matrix5d::Zero(), d);
  }
  EXPECT_DOUBLE_EQ(fixed.size_filter_m2(), 0.004);
  fixed.Classify(small, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_FALSE(d[0].crop);
}

TEST(CropClassifier, RegionGrowsWithTrackerUncertainty) {
  ClassifierOptions o;
  o.feature_sd_m = 0.01;
  o.plant_sd_m = 0.0;
  CropClassifier classifier(o);
  const std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0)};
  const std::vector<tracking::Feature> f = {FeatureAt(0.06, 1.0, 0.02)};  // below sure_crop_area
  std::vector<BlobDecision> d;
  classifier.Classify(f, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_FALSE(d[0].crop);  // γ² = 36 with σ = 1 cm
  geometry::Matrix5d p = geometry::Matrix5d::Zero();
  p(0, 0) = 0.03 * 0.03;  // σ(t_x) = 3 cm: γ² = 36 / 10 = 3.6
  classifier.Classify(f, crops, p, d);
  EXPECT_TRUE(d[0].crop);
  EXPECT_NEAR(d[0].gamma2, 0.0036 / 0.001, 1e-9);
}

TEST(CropClassifier, WithoutPredictionsEverythingIsWeed) {
  CropClassifier classifier(ClassifierOptions{});
  std::vector<BlobDecision> d;
  const std::vector<tracking::Feature> f = {FeatureAt(0.0, 1.0, 0.05)};
  classifier.Classify(f, {}, geometry::Matrix5d::Zero(), d);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_FALSE(d[0].crop);
  EXPECT_TRUE(std::isinf(d[0].gamma2));
}

TEST(CropClassifier, PredictionsComeFromTheGrid) {
  const geometry::CameraModel camera(geometry::testing::ThesisCamera());
  const geometry::GridModel model(camera, geometry::GridModelOptions{});
  geometry::GridState s;
  s.offset_m = 0.02;
  s.forward_m = 1.2;
  const std::vector<PredictedCrop> crops = PredictCrops(model, s);
  ASSERT_FALSE(crops.empty());
  for (const PredictedCrop& c : crops) {
    const Eigen::Vector2d expected = geometry::PlantInVehicle(s, c.m, c.n);
    EXPECT_NEAR((c.ground_m - expected).norm(), 0.0, 1e-12);
    EXPECT_NEAR(c.jacobian(0, 0), 1.0, 1e-12);  // d x / d t_x at Ψ = 0
  }
}

TEST(CropClassifier, BadOptionsAreNamed) {
  ClassifierOptions o;
  o.assoc_chi2 = 0.0;
  o.feature_sd_m = -1.0;
  try {
    CropClassifier c(o);
    FAIL() << "expected InvalidOptionsError";
  } catch (const InvalidOptionsError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("assoc_chi2"), std::string::npos) << what;
    EXPECT_NE(what.find("feature_sd_m"), std::string::npos) << what;
  }
}

TEST(CropClassifier, SplitMergedLabelsEachPlantOfAMergedBlob) {
  ClassifierOptions o = SizeAndGate();
  o.split_cover_m = 0.0;  // the gate alone (cover: below)
  CropClassifier classifier(o);
  const std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0), CropAt(0.0, 1.45),
                                            CropAt(0.0, 1.9)};
  std::vector<Eigen::Vector2d> ground;
  std::vector<double> area;
  const double cell = 0.005;
  const auto disk = [&](double cx, double cy, double r) {
    for (double x = cx - r; x <= cx + r; x += cell) {
      for (double y = cy - r; y <= cy + r; y += cell) {
        if (std::hypot(x - cx, y - cy) > r) continue;
        ground.emplace_back(x, y);
        area.push_back(cell * cell);
      }
    }
  };
  disk(0.0, 1.0, 0.1);    // plant 1 (31 cm²)
  const size_t plant_1_end = ground.size();
  disk(0.0, 1.33, 0.13);  // plant 2, leaning back 12 cm and touching plant 1
  const size_t plants_end = ground.size();
  disk(0.0, 1.72, 0.02);  // a small weed nearer plant 3: its part fails the size filter
  disk(0.45, 1.2, 0.03);  // a weed beyond every prediction's split radius
  // The whole blob: centroid between the plants, outside every region.
  std::vector<tracking::Feature> whole(1);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& g : ground) sum += g;
  whole[0] = FeatureAt(sum.x() / ground.size(), sum.y() / ground.size(), 0.1);
  std::vector<BlobDecision> d;
  classifier.Classify(whole, crops, geometry::Matrix5d::Zero(), d);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_FALSE(d[0].crop);

  std::vector<uint8_t> crop;
  // Split at y = 1.225 (halfway): plant 1's part (its disk and plant 2's
  // sliver below 1.225) centres within 1 cm of 1.0 and associates; plant 2's
  // part centres 11 cm short of 1.45, outside a 1 cm region.
  EXPECT_EQ(classifier.SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(), crop),
            1);
  ASSERT_EQ(crop.size(), ground.size());
  for (size_t i = 0; i < plants_end; ++i) {
    EXPECT_EQ(crop[i], ground[i].y() < 1.225 ? 1 : 0) << i;
  }
  EXPECT_GT(plants_end, plant_1_end);
  for (size_t i = plants_end; i < ground.size(); ++i) EXPECT_EQ(crop[i], 0) << i;

  // A wider gate for parts alone (plant 2's part: centroid 11 cm off with
  // σ 1 cm, γ² about 11²) makes it crop too; the whole blob is still weed.
  o.split_assoc_chi2 = 150.0;
  CropClassifier lenient(o);
  EXPECT_EQ(lenient.SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(), crop), 2);
  for (size_t i = 0; i < plants_end; ++i) EXPECT_EQ(crop[i], 1) << i;
  lenient.Classify(whole, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_FALSE(d[0].crop);
  o.split_assoc_chi2 = 100.0;  // below its γ²: still weed
  EXPECT_EQ(CropClassifier(o).SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(),
                                          crop),
            1);
  o.split_assoc_chi2 = 9.21;

  // Plant 2's part has plant matter at its predicted position (its disk
  // reaches 1.46 m): with a 2 cm cover it is that crop whatever its cut
  // centroid; the small weed's part (16 cm short of 1.9 m) is not.
  o.split_cover_m = 0.02;
  EXPECT_EQ(CropClassifier(o).SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(),
                                          crop),
            2);
  for (size_t i = 0; i < plants_end; ++i) EXPECT_EQ(crop[i], 1) << i;
  for (size_t i = plants_end; i < ground.size(); ++i) EXPECT_EQ(crop[i], 0) << i;
  o.split_cover_m = 0.0;

  // With a wide association region plant 2's part is crop too: two parts.
  o.feature_sd_m = 0.1;
  CropClassifier wide(o);
  EXPECT_EQ(wide.SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(), crop), 2);
  for (size_t i = 0; i < plants_end; ++i) EXPECT_EQ(crop[i], 1) << i;
  for (size_t i = plants_end; i < ground.size(); ++i) EXPECT_EQ(crop[i], 0) << i;

  // Mismatched inputs are refused, naming both counts.
  area.pop_back();
  EXPECT_THROW(classifier.SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(), crop),
               std::invalid_argument);
  // No predictions: nothing is crop.
  area.push_back(cell * cell);
  EXPECT_EQ(classifier.SplitMerged(ground, area, false, {}, geometry::Matrix5d::Zero(), crop), 0);
  for (uint8_t c : crop) EXPECT_EQ(c, 0);
}

// A leaf cut off a crop by segmentation: under the size filter, it is weed
// by the thesis's rule; within the crops' typical radius of a prediction a
// crop blob of the same frame associated with, it is that crop's leaf.
TEST(CropClassifier, ASmallBlobBesideACropFoundIsItsLeaf) {
  ClassifierOptions o = SizeAndGate();
  o.crop_size_min_samples = 3;
  o.fragment_reach = 1.0;
  CropClassifier classifier(o);
  const std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0), CropAt(0.0, 1.5)};
  std::vector<BlobDecision> d;
  for (int i = 0; i < 3; ++i) {  // whole crops of 0.01 m²: radius 5.6 cm
    classifier.Classify(std::vector<tracking::Feature>{FeatureAt(0.0, 1.0, 0.01)}, crops,
                        geometry::Matrix5d::Zero(), d);
  }
  ASSERT_NEAR(classifier.crop_reach_m(), std::sqrt(0.01 / M_PI), 1e-12);
  const std::vector<tracking::Feature> frame = {
      FeatureAt(0.0, 1.0, 0.01),            // the crop, found
      FeatureAt(0.05, 1.0, 0.0005),         // a leaf 5 cm off it: crop
      FeatureAt(0.07, 1.0, 0.0005),         // 7 cm off: beyond the reach, weed
      FeatureAt(0.0, 1.54, 0.0005),         // 4 cm off a crop not found: weed
      FeatureAt(-0.05, 1.0, 0.0005, true),  // cut by the border: as before (weed)
  };
  classifier.Classify(frame, crops, geometry::Matrix5d::Zero(), d);
  ASSERT_EQ(d.size(), 5u);
  EXPECT_TRUE(d[0].crop && d[0].associated && !d[0].fragment);
  EXPECT_TRUE(d[1].crop && d[1].fragment);
  EXPECT_FALSE(d[1].associated);  // marks no map cells
  EXPECT_EQ(d[1].m, 0);
  EXPECT_FALSE(d[2].crop);
  EXPECT_FALSE(d[3].crop);
  EXPECT_FALSE(d[4].crop);
  // Off: the thesis's rule.
  o.fragment_reach = 0.0;
  CropClassifier thesis(o);
  for (int i = 0; i < 3; ++i) {
    thesis.Classify(std::vector<tracking::Feature>{FeatureAt(0.0, 1.0, 0.01)}, crops,
                    geometry::Matrix5d::Zero(), d);
  }
  thesis.Classify(frame, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_FALSE(d[1].crop);
}

// A 3-week crop that segmentation found small: under the size filter, but
// alone in its prediction's region it is that crop.
TEST(CropClassifier, ASmallBlobAloneInACropsRegionIsThatCrop) {
  ClassifierOptions o = SizeAndGate();  // filter 0.004 m²
  o.lone_crop_fraction = 0.25;
  o.fragment_reach = 0.0;
  CropClassifier classifier(o);
  std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0), CropAt(0.0, 1.5), CropAt(0.0, 2.0)};
  for (int m = 0; m < 3; ++m) crops[static_cast<size_t>(m)].m = m;
  const std::vector<tracking::Feature> frame = {
      FeatureAt(0.01, 1.0, 0.002),          // alone at the first: crop
      FeatureAt(0.0, 1.5, 0.02),            // the second, whole
      FeatureAt(0.01, 1.51, 0.002),         // small beside it: weed (the crop is taken)
      FeatureAt(0.01, 2.0, 0.0009),         // under a quarter of the filter: weed
      FeatureAt(0.1, 1.0, 0.002),           // outside the region: weed
      FeatureAt(0.0, 2.01, 0.002, true),    // cut by the border: as before
  };
  std::vector<BlobDecision> d;
  classifier.Classify(frame, crops, geometry::Matrix5d::Zero(), d);
  ASSERT_EQ(d.size(), 6u);
  EXPECT_TRUE(d[0].crop && d[0].associated && d[0].lone);
  EXPECT_EQ(d[0].m, 0);
  EXPECT_NEAR(d[0].predicted_ground_m.y(), 1.0, 1e-12);
  EXPECT_TRUE(d[1].crop);
  EXPECT_FALSE(d[2].crop);
  EXPECT_FALSE(d[3].crop);
  EXPECT_FALSE(d[4].crop);
  EXPECT_TRUE(d[5].crop && !d[5].lone);  // clipped and associated: crop by the thesis's rule already
  // Lone crops do not teach the size filter (it would sink with them).
  for (int k = 0; k < 40; ++k) classifier.Classify(frame, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_NEAR(classifier.size_filter_m2(), 0.004, 1e-12);
  // Off: the thesis's rule, under the size filter is weed.
  o.lone_crop_fraction = 0.0;
  CropClassifier thesis(o);
  thesis.Classify(frame, crops, geometry::Matrix5d::Zero(), d);
  EXPECT_FALSE(d[0].crop);
  o.lone_crop_fraction = 1.5;
  EXPECT_THROW(CropClassifier{o}, InvalidOptionsError);
}

// A crop entering the view: the image border cuts its leaves 5 cm from
// its root, which lies beyond the border. Its visible part neither reaches
// the prediction (2 cm cover) nor centres on it; cut by the border, it is
// that crop once plant matter lies within the crops' typical radius
// (learnt from whole crops: 0.01 m², r = 5.6 cm) of the prediction.
TEST(CropClassifier, ACutBlobWithinACropsReachOfItsPredictionIsThatCrop) {
  ClassifierOptions o = SizeAndGate();
  o.crop_size_min_samples = 5;
  CropClassifier classifier(o);
  const std::vector<PredictedCrop> crops = {CropAt(0.0, 1.0)};
  std::vector<Eigen::Vector2d> ground;
  std::vector<double> area;
  for (double x = -0.06; x <= 0.06; x += 0.005) {
    for (double y = 1.05; y <= 1.12; y += 0.005) {
      ground.emplace_back(x, y);
      area.push_back(0.005 * 0.005);
    }
  }
  std::vector<uint8_t> crop;
  // Before any whole crop was seen there is no reach: weed either way.
  EXPECT_DOUBLE_EQ(classifier.crop_reach_m(), 0.0);
  EXPECT_EQ(classifier.SplitMerged(ground, area, true, crops, geometry::Matrix5d::Zero(), crop), 0);
  std::vector<BlobDecision> d;
  for (int i = 0; i < 5; ++i) {
    classifier.Classify(std::vector<tracking::Feature>{FeatureAt(0.0, 1.0, 0.01)}, crops,
                        geometry::Matrix5d::Zero(), d);
  }
  EXPECT_NEAR(classifier.median_crop_area_m2(), 0.01, 1e-12);
  EXPECT_NEAR(classifier.crop_reach_m(), std::sqrt(0.01 / M_PI), 1e-12);
  EXPECT_EQ(classifier.SplitMerged(ground, area, true, crops, geometry::Matrix5d::Zero(), crop), 1);
  for (const uint8_t c : crop) EXPECT_EQ(c, 1);
  // Not cut by the border: as before, weed (its centroid is 8.5 cm off).
  EXPECT_EQ(classifier.SplitMerged(ground, area, false, crops, geometry::Matrix5d::Zero(), crop), 0);
  // Beyond the reach (the part starts 5 cm from the root; 0.8 × 5.6 cm
  // = 4.5 cm): weed.
  o.split_clipped_reach = 0.8;
  CropClassifier shorter(o);
  for (int i = 0; i < 5; ++i) {
    shorter.Classify(std::vector<tracking::Feature>{FeatureAt(0.0, 1.0, 0.01)}, crops,
                     geometry::Matrix5d::Zero(), d);
  }
  EXPECT_EQ(shorter.SplitMerged(ground, area, true, crops, geometry::Matrix5d::Zero(), crop), 0);
}

// Points on a 2 mm grid inside a lobed outline R(θ) = R(1 − d + d|cos(kθ/2)|)
// about `centre` (d = 0: a disc).
std::vector<Eigen::Vector2d> Outline(const Eigen::Vector2d& centre, double r, double d, int lobes) {
  std::vector<Eigen::Vector2d> out;
  for (double x = -r; x <= r; x += 0.002) {
    for (double y = -r; y <= r; y += 0.002) {
      const double rt = r * (1.0 - d + d * std::abs(std::cos(0.5 * lobes * std::atan2(y, x))));
      if (std::hypot(x, y) <= rt) out.push_back(centre + Eigen::Vector2d(x, y));
    }
  }
  return out;
}

TEST(BeyondCropOutline, AWholeCropHasNothingBeyond) {
  std::vector<uint8_t> beyond;
  // A disc reaches 2.0 sd of its outline ellipse, a lobed outline of lobe
  // depth 0.25 (the crop profiles') 2.16 sd at its leaf tips.
  EXPECT_EQ(BeyondCropOutline(Outline({0.3, 1.0}, 0.1, 0.0, 0), 2.2, beyond), 0);
  EXPECT_EQ(BeyondCropOutline(Outline({0.3, 1.0}, 0.1, 0.25, 7), 2.2, beyond), 0);
  // Stretched along the line of sight (the oblique view): the ellipse follows.
  std::vector<Eigen::Vector2d> stretched = Outline({0.0, 0.0}, 0.1, 0.25, 7);
  for (Eigen::Vector2d& p : stretched) p.y() *= 1.4;
  EXPECT_EQ(BeyondCropOutline(stretched, 2.2, beyond), 0);
  // Beyond 1.9 sd of a lobed outline: its leaf tips.
  EXPECT_GT(BeyondCropOutline(Outline({0.3, 1.0}, 0.1, 0.25, 7), 1.9, beyond), 0);
}

TEST(BeyondCropOutline, AWeedMergedAtTheLeafTipsIsBeyond) {
  std::vector<Eigen::Vector2d> points = Outline({0.0, 0.0}, 0.1, 0.25, 7);
  const size_t crop_points = points.size();
  const Eigen::Vector2d weed(0.0, 0.125);  // a 2 cm weed against the leaf tips
  for (const Eigen::Vector2d& p : Outline(weed, 0.02, 0.0, 0)) {
    if (p.norm() > 0.1) points.push_back(p);  // where the crop's leaves are not
  }
  std::vector<uint8_t> beyond;
  const int n = BeyondCropOutline(points, 2.2, beyond);
  ASSERT_EQ(beyond.size(), points.size());
  int in_weed = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!beyond[i]) continue;
    EXPECT_LT((points[i] - weed).norm(), 0.021) << "flagged a crop point at " << points[i].transpose();
    in_weed += i >= crop_points;
  }
  EXPECT_EQ(in_weed, n);
  // The weed's outer part: its points beyond 0.12 m (2.2 sd of the lobed
  // outline, sd 0.046 m with the weed, is about 0.105 m) are all flagged.
  int outer = 0, outer_flagged = 0;
  for (size_t i = crop_points; i < points.size(); ++i) {
    if (points[i].norm() > 0.12) ++outer, outer_flagged += beyond[i];
  }
  EXPECT_GT(outer, 20);
  EXPECT_EQ(outer_flagged, outer);
}

TEST(BeyondCropOutline, OffOrTooFewPointsFlagsNothing) {
  std::vector<uint8_t> beyond;
  std::vector<Eigen::Vector2d> points = Outline({0.0, 0.0}, 0.1, 0.0, 0);
  points.emplace_back(0.5, 0.0);
  EXPECT_EQ(BeyondCropOutline(points, 0.0, beyond), 0);
  EXPECT_EQ(beyond.size(), points.size());
  const std::vector<Eigen::Vector2d> few(points.begin(), points.begin() + 7);
  EXPECT_EQ(BeyondCropOutline(few, 2.2, beyond), 0);
  // All on one line: no ellipse.
  std::vector<Eigen::Vector2d> line;
  for (int i = 0; i < 20; ++i) line.emplace_back(0.01 * i, 0.0);
  EXPECT_EQ(BeyondCropOutline(line, 2.2, beyond), 0);
  // A lone point far off is beyond.
  EXPECT_EQ(BeyondCropOutline(points, 2.2, beyond), 1);
  EXPECT_EQ(beyond.back(), 1);
}

}  // namespace
}  // namespace plantscale::classify

namespace plantscale::classify {
namespace {

// The learned model's class decides where it is sure; the grid's rule
// elsewhere; a sure weed loses its association with the crop it touches.
TEST(FuseLearned, TheModelDecidesWhereSureAndTheRuleElsewhere) {
  ClassifierOptions o;
  o.learned_min_confidence = 0.6;
  BlobDecision rule;
  rule.crop = true;
  rule.associated = true;
  rule.m = 1;
  BlobDecision d = rule;
  FuseLearned(2, 0.9, o, d);  // sure weed inside a crop's region
  EXPECT_FALSE(d.crop);
  EXPECT_FALSE(d.associated);
  EXPECT_TRUE(d.learned);
  EXPECT_EQ(d.learned_class, 2);
  EXPECT_DOUBLE_EQ(d.learned_confidence, 0.9);
  d = rule;
  FuseLearned(2, 0.59, o, d);  // unsure: the rule's crop stands
  EXPECT_TRUE(d.crop);
  EXPECT_TRUE(d.associated);
  EXPECT_FALSE(d.learned);
  EXPECT_EQ(d.learned_class, 2);
  BlobDecision weed;  // the rule's weed (outside every region)
  d = weed;
  FuseLearned(1, 0.8, o, d);  // sure crop
  EXPECT_TRUE(d.crop);
  EXPECT_FALSE(d.associated);  // the grid did not place it
  EXPECT_TRUE(d.learned);
  d = weed;
  FuseLearned(0, 0.99, o, d);  // the model calls it soil: the rule stands
  EXPECT_FALSE(d.crop);
  EXPECT_FALSE(d.learned);
  o.learned_min_confidence = 1.5;  // never
  d = rule;
  FuseLearned(2, 1.0, o, d);
  EXPECT_TRUE(d.crop);
  EXPECT_FALSE(d.learned);
}

}  // namespace
}  // namespace plantscale::classify
