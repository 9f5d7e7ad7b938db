#include "engine/tracking/height_from_size.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "engine/tracking/observation_test_fixture.h"

// Height from size: δh from a blob's size against its band's mean, the
// bands' means, and the pseudo-observation's Jacobian (a unit row at the
// plant's δh) against the change of its residual with the state.

namespace plantscale::tracking {
namespace {

using geometry::GridState;
using testing::FieldObservation;

double AreaOfRadius(double r) { return std::numbers::pi * r * r; }

TEST(HeightFromSize, ABlobsSizeRatioScalesItsCentroidHeight) {
  TrackerOptions o;  // e = 0.03 m, ratios within [1/1.5, 1.5]
  const double band = 0.10;
  const double h_l = 0.08;
  // As big as the band's mean: the crop's own height.
  EXPECT_NEAR(*HeightFromBlob(o, AreaOfRadius(band), band, h_l), 0.0, 1e-15);
  // (ρ + e) = 1.2 (ρ̄ + e): 20 % taller.
  EXPECT_NEAR(*HeightFromBlob(o, AreaOfRadius(1.2 * 0.13 - 0.03), band, h_l), 0.2 * h_l, 1e-15);
  EXPECT_NEAR(*HeightFromBlob(o, AreaOfRadius(0.8 * 0.13 - 0.03), band, h_l), -0.2 * h_l, 1e-15);
  // Merged or cut: beyond 1.5 either way says nothing.
  EXPECT_FALSE(HeightFromBlob(o, AreaOfRadius(1.6 * 0.13 - 0.03), band, h_l));
  EXPECT_FALSE(HeightFromBlob(o, AreaOfRadius(0.13 / 1.6 - 0.03), band, h_l));
}

TEST(HeightFromSize, ObservesEachMatchedPlantsHeightWithAUnitJacobian) {
  FieldObservation field;
  field.options.crop_radius_m = 0.14;
  field.options.crop_height_m = 0.112;
  const TrackerOptions& o = field.options;
  ASSERT_TRUE(o.HeightFromSize());
  const int image_height = field.camera.height();
  HeightFromSize sizes(o, image_height);
  // Blobs in the band of image rows at 60 % of the height.
  const Eigen::Vector2d px(0.5 * field.camera.width(), 0.6 * image_height);
  const int band = static_cast<int>(px.y() * o.size_bands / image_height);
  const auto blob = [&](double radius_m) {
    Feature f;
    f.image_px = px;
    f.area_m2 = AreaOfRadius(radius_m);
    return f;
  };
  GridFilter filter(o);
  filter.Restart(GridState{0.0, 0.3, 0.0, 0.475, 0.45}, 1e-4 * geometry::Matrix5d::Identity());
  filter.AddPlant(0, 0);
  filter.AddPlant(1, 0);
  const std::vector<Feature> features{blob(0.12), blob(0.09)};
  const std::vector<SizeMatch> matches{{0, 0, 0}, {1, 0, 1}};
  // Too few blobs in the band: no rows.
  EXPECT_EQ(sizes.Observe(filter, field.heights, features, matches).factor.rows(), 0);
  // Its mean, the plain mean of the first blobs (0.09, 0.11 alternately).
  std::vector<Feature> learnt;
  for (int i = 0; i < o.size_min_samples; ++i) learnt.push_back(blob(i % 2 ? 0.11 : 0.09));
  std::vector<SizeMatch> learnt_matches;
  for (int i = 0; i < o.size_min_samples; ++i) learnt_matches.push_back({0, 0, i});
  sizes.Learn(learnt, learnt_matches);
  EXPECT_EQ(sizes.band_samples(band), o.size_min_samples);
  EXPECT_NEAR(sizes.band_radius_m(band), 0.10, 1e-12);

  const PseudoObservation z = sizes.Observe(filter, field.heights, features, matches);
  ASSERT_EQ(z.factor.rows(), 2);
  const double sd = o.size_height_sd_m;
  const double h_l = field.heights.HeightAt(px);
  const int first = filter.OffsetIndex(0, 0) + 2;
  const int second = filter.OffsetIndex(1, 0) + 2;
  EXPECT_EQ(z.support, (std::vector<int>{first, second}));
  EXPECT_NEAR(z.factor(0, first), 1.0 / sd, 1e-12);
  EXPECT_NEAR(z.factor.row(0).cwiseAbs().sum(), 1.0 / sd, 1e-12);
  EXPECT_NEAR(z.residual(0), h_l * ((0.12 + 0.03) / 0.13 - 1.0) / sd, 1e-9);
  EXPECT_NEAR(z.residual(1), h_l * ((0.09 + 0.03) / 0.13 - 1.0) / sd, 1e-9);
  // Finite differences of the model h(x) = δh: move the state by an update
  // and the residual moves by −L Δx.
  const Eigen::VectorXd x0 = filter.x();
  filter.Apply(z);
  const Eigen::VectorXd dx = filter.x() - x0;
  ASSERT_GT(dx.cwiseAbs().maxCoeff(), 1e-3);
  const PseudoObservation moved = sizes.Observe(filter, field.heights, features, matches);
  EXPECT_LT((moved.residual - (z.residual - z.factor * dx)).cwiseAbs().maxCoeff(), 1e-9);
  // Learnt after observing: the band's mean moves towards these blobs.
  sizes.Learn(features, matches);
  EXPECT_NEAR(sizes.band_radius_m(band), 0.10 + (0.12 - 0.10) / 31.0 + (0.09 - (0.10 + 0.02 / 31.0)) / 32.0,
              1e-12);
}

}  // namespace
}  // namespace plantscale::tracking
