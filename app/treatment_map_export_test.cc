#include "app/treatment_map_export.h"

#include <gtest/gtest.h>

namespace plantscale::app {
namespace {

TEST(TreatmentMapExport, ClassLayerAndPlantsCarryOver) {
  treatment::TreatmentMapOptions mo;
  mo.majority_threshold = 1;
  treatment::TreatmentMap map(mo);
  const treatment::Quad square = {Eigen::Vector2d(0.08, 0.98), Eigen::Vector2d(0.12, 0.98),
                                  Eigen::Vector2d(0.12, 1.02), Eigen::Vector2d(0.08, 1.02)};
  map.AddFootprint(square, true);
  treatment::PlantRegistry registry;
  classify::ClassifierOptions c;
  classify::BlobDecision d;
  d.crop = true;
  d.area_m2 = 0.0314;
  registry.Observe({0.1, 1.0}, d);
  registry.Explain(map, treatment::SprayMode::kCrop, c);
  const maps::CropMap out = ToCropMap(map, registry);
  EXPECT_NEAR(out.grid().resolution_m(), 0.01333, 1e-12);
  EXPECT_EQ(out.grid().cols(), map.columns());
  const auto cell = out.grid().FindCell({0.1, 1.0});
  ASSERT_TRUE(cell);
  EXPECT_EQ(out.ClassAt(*cell), maps::CellClass::kCrop);
  const auto far = out.grid().FindCell({-1.0, 1.0});
  ASSERT_TRUE(far);
  EXPECT_EQ(out.ClassAt(*far), maps::CellClass::kSoil);
  ASSERT_EQ(out.plants().size(), 1u);
  EXPECT_EQ(out.plants()[0].kind, maps::PlantKind::kCrop);
  EXPECT_NEAR(out.plants()[0].radius_m, 0.1, 1e-4);
  EXPECT_NE(out.plants()[0].why.find("crop (1 crop / 0 weed votes)"), std::string::npos);
}

}  // namespace
}  // namespace plantscale::app
