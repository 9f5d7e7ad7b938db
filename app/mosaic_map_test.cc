#include "app/mosaic_map.h"

#include <gtest/gtest.h>

namespace plantscale::app {
namespace {

// A 4 x 3 mosaic with every label and one plant of radius 0 (its disc is
// its root cell, already plant).
motion::MosaicMap SmallMosaic() {
  motion::MosaicMap m;
  m.grid.resolution_m = 0.05;
  m.grid.origin_m = {-0.1, 0.2};
  m.grid.cols = 4;
  m.grid.rows = 3;
  constexpr uint8_t s = motion::kSoilLabel, p = motion::kPlantLabel, w = motion::kWeedLabel,
                    u = motion::kUnknownLabel;
  m.labels = {s, w, p, u,  // row 0 (smallest y)
              s, p, w, s,  //
              u, u, s, w};
  m.plants.push_back({m.grid.CellCentre({1, 1}), 0.0});
  m.frames = 7;
  return m;
}

TEST(MosaicMapTest, TheCropMapKeepsTheGridAndEveryCellValue) {
  const motion::MosaicMap mosaic = SmallMosaic();
  const maps::CropMap map = ToCropMap(mosaic);
  EXPECT_EQ(map.grid().resolution_m(), mosaic.grid.resolution_m);
  EXPECT_EQ(map.grid().origin_m(), mosaic.grid.origin_m);
  EXPECT_EQ(map.grid().cols(), mosaic.grid.cols);
  EXPECT_EQ(map.grid().rows(), mosaic.grid.rows);
  // The plant paints only its own cell, already plant: no cell changes.
  EXPECT_EQ(map.layers().cls, mosaic.labels);
  EXPECT_EQ(map.ClassAt({2, 0}), maps::CellClass::kCrop);
  EXPECT_EQ(map.ClassAt({1, 0}), maps::CellClass::kWeed);
  EXPECT_EQ(map.ClassAt({3, 0}), maps::CellClass::kUnknown);
  EXPECT_EQ(map.ClassAt({0, 1}), maps::CellClass::kSoil);
  EXPECT_EQ(map.metadata().at("frames"), "7");
}

TEST(MosaicMapTest, PlantsAreRegisteredAsCropsAndCounted) {
  const maps::CropMap map = ToCropMap(SmallMosaic());
  ASSERT_EQ(map.plants().size(), 1U);
  const maps::MapPlant& p = map.plants()[0];
  EXPECT_EQ(p.id, 1);
  EXPECT_EQ(p.kind, maps::PlantKind::kCrop);
  EXPECT_EQ(p.position_m, map.grid().CellCentre({1, 1}));
  EXPECT_EQ(map.layers().crop_count[map.grid().Index({1, 1})], 1);
}

}  // namespace
}  // namespace plantscale::app
