#include "engine/tracking/association.h"

#include <gtest/gtest.h>

#include <vector>

// One-to-one nearest-neighbour association (eq. 6.6) and the
// observability check (§4.5).

namespace plantscale::tracking {
namespace {

TEST(Association, OneFeaturePerPlantAndOnePlantPerFeatureSmallestGammaFirst) {
  // Plant 0 is nearest feature 1, but plant 1 is nearer still: plant 0
  // takes feature 0; plant 2 has only feature 1, taken.
  const std::vector<Candidate> gated{{0, 0, 1.0}, {0, 1, 0.5}, {1, 1, 0.2}, {1, 0, 3.0}, {2, 1, 0.1}};
  const std::vector<Candidate> matches = Associate(gated, 3, 2);
  ASSERT_EQ(matches.size(), 2u);
  EXPECT_EQ(matches[0].plant, 2);
  EXPECT_EQ(matches[0].feature, 1);
  EXPECT_EQ(matches[1].plant, 0);
  EXPECT_EQ(matches[1].feature, 0);
  EXPECT_DOUBLE_EQ(matches[1].gamma2, 1.0);
}

TEST(Association, TheSpacingsNeedAThirdMatchOffTheOthersRowAndLine) {
  std::vector<geometry::GridPlant> in_view(4);
  const int mn[4][2] = {{0, 0}, {1, 0}, {2, 0}, {1, 1}};
  for (int i = 0; i < 4; ++i) in_view[static_cast<size_t>(i)].m = mn[i][0], in_view[static_cast<size_t>(i)].n = mn[i][1];
  TrackerOptions o;
  const auto observable = [&](const std::vector<Candidate>& matches, FrameReport& report) {
    report.matched = static_cast<int>(matches.size());
    report.predicted = static_cast<int>(in_view.size());
    return Observable(o, matches, in_view, report);
  };
  FrameReport one_row;
  EXPECT_FALSE(observable({{0, 0, 0.1}, {1, 1, 0.1}, {2, 2, 0.1}}, one_row));
  EXPECT_EQ(one_row.skipped_reason, "not observable: 3 matched feature(s) of 4 predicted plants, all on one row");
  FrameReport two_rows;
  EXPECT_TRUE(observable({{0, 0, 0.1}, {1, 1, 0.1}, {3, 2, 0.1}}, two_rows));
  FrameReport two;
  EXPECT_FALSE(observable({{0, 0, 0.1}, {3, 2, 0.1}}, two));
  EXPECT_EQ(two.skipped_reason, "not observable: 2 matched feature(s) of 4 predicted plants (3 needed)");
  // The fixed grid (3 states) needs two.
  o.estimate_spacing = false;
  FrameReport fixed;
  EXPECT_TRUE(observable({{0, 0, 0.1}, {3, 2, 0.1}}, fixed));
}

}  // namespace
}  // namespace plantscale::tracking
