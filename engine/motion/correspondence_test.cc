#include "engine/motion/correspondence.h"

#include <gtest/gtest.h>

#include <random>

namespace plantscale::motion {
namespace {

TEST(Correspondence, SimilarityIsEquationSixWithWrappedOrientation) {
  EXPECT_NEAR(SimilarityDistance({0.3, 0.0}, {0.0, 0.4}), 0.5, 1e-12);
  EXPECT_NEAR(SimilarityDistance({0.0, 3.1}, {0.0, -3.1}), 2.0 * M_PI - 6.2, 1e-12);
  EXPECT_NEAR(SimilarityDistance({1.0, 0.0}, {0.0, 0.0}, 2.0, 1.0), 2.0, 1e-12);
}

// §3.2: the ellipse lies along the motion; it holds the track's true
// position and positions up to ±30 % of depth, not a point beside them.
TEST(Correspondence, EpipolarSearchRegionLiesAlongTheMotion) {
  const PlanarMotion previous{0.0, {0.0, -0.25}};
  const Eigen::Vector2d feature(0.1, 0.4);
  const SearchRegion r = EpipolarSearchRegion(feature, previous, 0.3, 0.01);
  EXPECT_NEAR(r.a.y(), 0.4 + 0.25 / 0.7, 1e-12);
  EXPECT_NEAR(r.b.y(), 0.4 + 0.25 / 1.3, 1e-12);
  EXPECT_TRUE(r.Contains({0.1, 0.65}));
  EXPECT_TRUE(r.Contains({0.1, 0.75}));
  EXPECT_FALSE(r.Contains({0.16, 0.65}));  // 6 cm aside
  EXPECT_FALSE(r.Contains({0.1, 0.4}));    // no motion at all
}

TEST(Correspondence, TwoWayMatchesAreMinimaOfRowAndColumn) {
  Eigen::MatrixXd dm(3, 3);
  dm << 0.1, 0.5, kNoMatch,  //
      0.2, 0.9, 0.3,         //
      kNoMatch, 0.4, 0.8;
  const std::vector<Match> m = TwoWayMatches(dm);
  // (0,0) both ways; row 1's minimum (0,… col 0) is taken by row 0;
  // (2,1) is row 2's minimum and column 1's.
  ASSERT_EQ(m.size(), 2U);
  EXPECT_EQ(m[0], Match(0, 0));
  EXPECT_EQ(m[1], Match(2, 1));
  EXPECT_TRUE(TwoWayMatches(Eigen::MatrixXd::Constant(2, 2, kNoMatch)).empty());
}

TEST(Correspondence, SequentialClusteringWithTwoThresholds) {
  std::vector<Eigen::Vector3d> p{{0, 0, 0}, {0.004, 0, 0}, {1, 1, 0}, {0.002, 0.003, 0},
                                 {1.005, 1, 0}, {0.5, 0.5, 0}};
  const std::vector<int> label = SequentialCluster(p, 0.01, 0.02);
  EXPECT_EQ(label[0], label[1]);
  EXPECT_EQ(label[0], label[3]);
  EXPECT_EQ(label[2], label[4]);
  EXPECT_NE(label[0], label[2]);
  EXPECT_NE(label[5], label[0]);
  EXPECT_NE(label[5], label[2]);
  // A point between the thresholds waits; with nothing else to join it
  // opens its own cluster in the end.
  const std::vector<int> waiting = SequentialCluster(
      std::vector<Eigen::Vector3d>{{0, 0, 0}, {0.015, 0, 0}}, 0.01, 0.02);
  EXPECT_NE(waiting[0], waiting[1]);
}

TEST(Correspondence, HoughSelectionKeepsTheRigidMatchesAndFindsTheMotion) {
  const PlanarMotion truth{0.02, {0.005, -0.25}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Eigen::Vector2d> prev, cur;
  for (int i = 0; i < 8; ++i) {
    prev.emplace_back(u(rng), 0.7 + u(rng) / 3.0);
    cur.push_back(truth.Apply(prev.back()));
  }
  for (int i = 0; i < 4; ++i) {  // outliers: random pairs
    prev.emplace_back(u(rng), 0.7 + u(rng) / 3.0);
    cur.emplace_back(u(rng), 0.45 + u(rng) / 3.0);
  }
  const HoughResult h = HoughSelect(prev, cur, 0.0, HoughOptions{});
  std::vector<int> expected{0, 1, 2, 3, 4, 5, 6, 7};
  EXPECT_EQ(h.coherent, expected);
  EXPECT_NEAR(h.motion.psi_rad, truth.psi_rad, 0.3 * M_PI / 180.0 / 2.0 + 1e-9);  // half a step
  EXPECT_LT((h.motion.t_m - truth.t_m).norm(), 0.01);
}

TEST(Correspondence, FilterRejectsWrongDepthAndDirection) {
  const PlanarMotion m{0.0, {0.0, -0.25}};
  const Eigen::Vector2d p(0.0, 0.7);
  EXPECT_TRUE(ConsistentWithMotion(m, p, m.Apply(p), 0.3, 0.0873));
  EXPECT_TRUE(ConsistentWithMotion(m, p, p + 1.2 * m.t_m, 0.3, 0.0873));
  EXPECT_FALSE(ConsistentWithMotion(m, p, p + 1.6 * m.t_m, 0.3, 0.0873));  // depth −37 %
  EXPECT_FALSE(ConsistentWithMotion(m, p, p + Eigen::Vector2d(0.03, -0.25), 0.3, 0.0873));  // 6.8°
}

TEST(Correspondence, GreedyMatchingTakesTheSmallestEntriesFirst) {
  Eigen::MatrixXd cost(2, 3);
  cost << 0.5, 0.1, kNoMatch,  //
      0.2, 0.15, 0.9;
  const std::vector<Match> m = GreedyMatches(cost, {}, {});
  ASSERT_EQ(m.size(), 2U);
  EXPECT_EQ(m[0], Match(0, 1));
  EXPECT_EQ(m[1], Match(1, 0));
  EXPECT_EQ(GreedyMatches(cost, {1, 0}, {}).front(), Match(1, 1));  // row 0 already matched
}

}  // namespace
}  // namespace plantscale::motion
