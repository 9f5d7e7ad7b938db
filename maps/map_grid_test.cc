#include "maps/map_grid.h"

#include <gtest/gtest.h>

#include <random>

namespace plantscale::maps {
namespace {

MapGrid TestGrid() { return MapGrid({0.02, {-1.23, 4.56}, 57, 83}); }

TEST(MapGrid, IndexAndCellRoundTripForEveryCell) {
  const MapGrid g = TestGrid();
  for (size_t i = 0; i < g.size(); ++i) {
    const Cell c = g.CellOf(i);
    ASSERT_EQ(g.Index(c), i);
    ASSERT_TRUE(g.Contains(c));
  }
  EXPECT_EQ(g.size(), 57u * 83u);
}

TEST(MapGrid, CellCentreMapsBackToItsCellForEveryCell) {
  const MapGrid g = TestGrid();
  for (size_t i = 0; i < g.size(); ++i) {
    const Cell c = g.CellOf(i);
    ASSERT_EQ(g.CellAt(g.CellCentre(c)), c);
    ASSERT_EQ(g.FindCell(g.CellCentre(c)).value(), c);
    // Corner + half a cell is the centre (tolerance 1e-12 m).
    ASSERT_LT((g.CellCorner(c) + Eigen::Vector2d::Constant(0.01) - g.CellCentre(c)).norm(), 1e-12);
  }
}

TEST(MapGrid, WorldToCellToWorldIsWithinHalfACell) {
  const MapGrid g = TestGrid();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 10000; ++k) {
    const Eigen::Vector2d p =
        g.origin_m() + g.extent_m().cwiseProduct(Eigen::Vector2d(u(rng), u(rng)));
    const auto cell = g.FindCell(p);
    ASSERT_TRUE(cell.has_value());
    worst = std::max(worst, (g.CellCentre(*cell) - p).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, 0.01 + 1e-12);  // half of the 2 cm cell
  EXPECT_GT(worst, 0.009);         // and the bound is reached, not trivially 0
}

TEST(MapGrid, PointsOutsideHaveNoCell) {
  const MapGrid g = TestGrid();
  EXPECT_FALSE(g.FindCell(g.origin_m() - Eigen::Vector2d(1e-9, 0)).has_value());
  EXPECT_FALSE(g.FindCell(g.max_m()).has_value());  // max is exclusive
  EXPECT_FALSE(g.FindCell({std::nan(""), 5.0}).has_value());
  EXPECT_TRUE(g.FindCell(g.origin_m()).has_value());
}

TEST(MapGrid, CoveringContainsBothCornersOnAlignedCells) {
  const MapGrid g = MapGrid::Covering({-0.511, 0.033}, {0.777, 2.001}, 0.05);
  EXPECT_TRUE(g.FindCell({-0.511, 0.033}).has_value());
  EXPECT_TRUE(g.FindCell({0.777, 2.001}).has_value());
  EXPECT_NEAR(g.origin_m().x(), -0.55, 1e-12);
  EXPECT_NEAR(g.origin_m().y(), 0.0, 1e-12);
  EXPECT_EQ(g.cols(), 27);  // −0.55 … 0.80
  EXPECT_EQ(g.rows(), 41);  // 0 … 2.05
}

TEST(MapGrid, InvalidOptionsNameTheKey) {
  try {
    MapGrid({0.0, {0, 0}, 0, 5});
    FAIL() << "expected InvalidOptionsError";
  } catch (const InvalidOptionsError& e) {
    ASSERT_EQ(e.errors().size(), 2u);
    EXPECT_EQ(e.errors()[0].key, "resolution_m");
    EXPECT_EQ(e.errors()[1].key, "cols");
  }
}

}  // namespace
}  // namespace plantscale::maps
