#include "maps/crop_map.h"

#include <gtest/gtest.h>

#include "maps/map_merge.h"
#include "maps/test_maps.h"

namespace plantscale::maps {
namespace {

using testing::SyntheticMap;

TEST(CropMap, PlantsAreCountedInTheirRootCellAndPaintTheirFootprint) {
  const CropMap map = SyntheticMap();
  const MapGrid& g = map.grid();
  const size_t root = g.Index(*g.FindCell({0.0, 1.0}));
  EXPECT_EQ(map.layers().crop_count[root], 1);
  EXPECT_EQ(map.layers().weed_count[root], 0);
  EXPECT_EQ(map.ClassAt(*g.FindCell({0.05, 1.0})), CellClass::kCrop);  // inside r = 8 cm
  EXPECT_EQ(map.ClassAt(*g.FindCell({0.12, 1.0})), CellClass::kSoil);  // outside
  const size_t weed = g.Index(*g.FindCell({0.21, 2.11}));
  EXPECT_EQ(map.layers().weed_count[weed], 1);
  EXPECT_EQ(map.layers().treated[weed], 1);
  // A 3 cm weed covers the cells whose centres lie within 3 cm: 9 of 2 cm cells
  // around (0.21, 2.11), a cell centre (neighbours at 2 cm, diagonals at 2.83 cm).
  EXPECT_EQ(map.treated_cells(), 9u);
  int crops = 0;
  for (uint16_t n : map.layers().crop_count) crops += n;
  EXPECT_EQ(crops, 30);
}

TEST(CropMap, WeedWinsOverCropWhereFootprintsMeet) {
  CropMap map(MapGrid({0.02, {0, 0}, 10, 10}));
  map.AddPlant({1, {0.1, 0.1}, PlantKind::kWeed, 1, 0.03, false, ""});
  map.AddPlant({2, {0.1, 0.1}, PlantKind::kCrop, 1, 0.05, false, ""});
  EXPECT_EQ(map.ClassAt({5, 5}), CellClass::kWeed);
  EXPECT_EQ(map.ClassAt({6, 5}), CellClass::kCrop);     // 3.2 cm away: crop only
  EXPECT_EQ(map.ClassAt({0, 0}), CellClass::kUnknown);  // never observed
}

TEST(CropMap, DuplicateIdsAndNonFinitePositionsAreDataErrors) {
  CropMap map = SyntheticMap();
  EXPECT_THROW(map.AddPlant({1, {0, 0}, PlantKind::kCrop, 1, 0.1, false, ""}), DataError);
  EXPECT_THROW(map.AddPlant({5000, {std::nan(""), 0}, PlantKind::kCrop, 1, 0.1, false, ""}),
               DataError);
}

TEST(MapMerge, CountsAddAndPlantsMergeByIdAndPosition) {
  const CropMap a = SyntheticMap();
  CropMap b(MapGrid({0.02, {-0.5, 1.5}, 50, 50}));  // overlaps a, 25 × 50 cells offset
  b.MarkObserved({-0.5, 1.5}, {0.5, 2.5});
  b.AddPlant({1000, {0.22, 2.11}, PlantKind::kWeed, 0.95, 0.03, false, "seen again"});  // same id
  b.AddPlant(
      {77, {0.0, 2.01}, PlantKind::kCrop, 0.99, 0.08, false, "crop"});  // id 77 ≠ 15, same place
  b.AddPlant({5, {0.4, 2.4}, PlantKind::kWeed, 0.6, 0.02, true, "new weed"});  // id 5 taken
  const CropMap m = MergeMaps({a, b});
  EXPECT_EQ(m.grid(), a.grid());  // b lies inside a
  EXPECT_EQ(m.plants().size(), a.plants().size() + 1);
  const MapPlant* weed = m.FindPlant(1000);
  ASSERT_NE(weed, nullptr);
  EXPECT_NEAR(weed->confidence, 0.95, 1e-12);
  EXPECT_TRUE(weed->treated);
  EXPECT_NEAR(weed->position_m.x(), 0.21, 1e-12);  // first position kept
  const MapPlant* fresh = m.FindPlant(1002);       // max id (1001) + 1
  ASSERT_NE(fresh, nullptr);
  EXPECT_EQ(fresh->why, "new weed");
  const size_t cell = m.grid().Index(*m.grid().FindCell({0.0, 2.01}));
  EXPECT_EQ(m.layers().crop_count[cell], 2);  // counts add even for one plant seen twice
  EXPECT_EQ(m.metadata().at("merged_from"), "2 maps: synthetic test map; ?");
}

TEST(MapMerge, UnionGridGrowsAndKeepsCellsInPlace) {
  const CropMap a = SyntheticMap();
  CropMap b(MapGrid({0.02, {0.9, 5.4}, 20, 20}));  // sticks out of a by 30 cm × 30 cm
  b.AddPlant({1, {1.11, 5.71}, PlantKind::kWeed, 1, 0.01, true, "far"});
  const CropMap m = MergeMaps({a, b});
  EXPECT_NEAR(m.grid().max_m().x(), 1.3, 1e-9);
  EXPECT_NEAR(m.grid().max_m().y(), 5.8, 1e-9);
  EXPECT_EQ(m.grid().origin_m(), a.grid().origin_m());
  EXPECT_EQ(m.layers().weed_count[m.grid().Index(*m.grid().FindCell({1.11, 5.71}))], 1);
  EXPECT_EQ(m.ClassAt(*m.grid().FindCell({0.0, 1.0})), CellClass::kCrop);
  EXPECT_EQ(m.ClassAt(*m.grid().FindCell({1.25, 5.45})), CellClass::kUnknown);
}

TEST(MapMerge, MisalignedOrDifferentCellsAreDataErrors) {
  const CropMap a = SyntheticMap();
  EXPECT_THROW(MergeMaps({a, CropMap(MapGrid({0.02, {0.005, 0.0}, 5, 5}))}), DataError);
  EXPECT_THROW(MergeMaps({a, CropMap(MapGrid({0.05, {0.0, 0.0}, 5, 5}))}), DataError);
  EXPECT_THROW(MergeMaps({}), DataError);
}

}  // namespace
}  // namespace plantscale::maps
