#include "maps/sim_truth.h"

#include <gtest/gtest.h>

#include <fstream>

#include "maps/map_errors.h"
#include "maps/test_maps.h"

namespace plantscale::maps {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// A simulator output folder in miniature, with the headers of app/sim_output.cc.
void WriteSimFolder(const fs::path& dir, const std::string& plants_extra = "") {
  fs::create_directories(dir / "truth");
  std::ofstream(dir / "truth" / "plants.csv")
      << "plant_id,class,row,line,x_m,y_m,radius_m,height_m,fractured\n"
         "1,crop,0,0,0.01,0.5,0.1,0.08,0\n"
         "2,crop,1,0,0.475,0.51,0.1,0.08,0\n"
         "3,weed,0,-1,0.2,0.8,0.03,0.01,0\n"
         "4,weed,0,-1,0.3,9.0,0.03,0.01,0\n"  // never seen
      << plants_extra;
  std::ofstream(dir / "truth" / "visible_plants.csv")
      << "frame,instance,plant_id,class,row,line,x_m,y_m,vehicle_x_m,vehicle_y_m,radius_m,"
         "height_m,root_u_px,root_v_px,area_px,centroid_u_px,centroid_v_px\n"
         "0,1,1,crop,0,0,0.01,0.5,0,0,0.1,0.08,1,2,30,1,2\n"
         "0,2,2,crop,1,0,0.475,0.51,0,0,0.1,0.08,1,2,30,1,2\n"
         "1,1,3,weed,0,-1,0.2,0.8,0,0,0.03,0.01,,,5,1,2\n";
  std::ofstream(dir / "truth" / "lines.csv")
      << "line,y_m,row_spacing_m,plant_spacing_m\n0,0.5,0.475,0.45\n1,0.95,0.476,0.45\n";
  std::ofstream(dir / "run.json") << R"({"preset": "testbed", "seed": 4, "length_m": 1.0})";
}

TEST(SimTruth, BuildsTheMapOfTheSeenPlants) {
  TempDir dir;
  WriteSimFolder(dir.path());
  ASSERT_TRUE(IsSimulatorOutput(dir.path()));
  const CropMap map = LoadSimulatorTruth(dir.path());
  ASSERT_EQ(map.plants().size(), 3u);  // plant 4 was never in view
  EXPECT_EQ(map.FindPlant(4), nullptr);
  const MapPlant* weed = map.FindPlant(3);
  ASSERT_NE(weed, nullptr);
  EXPECT_TRUE(weed->treated);
  EXPECT_EQ(weed->kind, PlantKind::kWeed);
  EXPECT_EQ(weed->position_m, Eigen::Vector2d(0.2, 0.8));
  EXPECT_FALSE(map.FindPlant(1)->treated);
  EXPECT_EQ(map.metadata().at("source"), "simulator truth");
  EXPECT_EQ(map.metadata().at("preset"), "testbed");
  EXPECT_EQ(map.metadata().at("seed"), "4");
  // Extent: seen plants ± radius ± 0.25 m margin, on 2 cm cells.
  EXPECT_LE(map.grid().origin_m().x(), 0.01 - 0.1 - 0.25 + 1e-9);
  EXPECT_GE(map.grid().max_m().x(), 0.475 + 0.1 + 0.25 - 1e-9);
  EXPECT_NEAR(map.grid().resolution_m(), 0.02, 1e-15);
  // Rows 0 and 1 (crops' rows) through both plant lines: x = n·r̄(y).
  ASSERT_EQ(map.rows().size(), 2u);
  EXPECT_NEAR(map.rows()[1].points_m[1].x(), 0.476, 1e-12);
}

TEST(SimTruth, MalformedCsvNamesFileLineAndColumn) {
  TempDir dir;
  WriteSimFolder(dir.path(), "5,crop,0,1,abc,0.9,0.1,0.08,0\n");
  std::ofstream(dir.path() / "truth" / "visible_plants.csv", std::ios::app)
      << "2,1,5,crop,0,1,0,0.9,0,0,0.1,0.08,1,2,30,1,2\n";
  try {
    LoadSimulatorTruth(dir.path());
    FAIL() << "expected DataError";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("plants.csv: line 6, column x_m: 'abc' is not a number"),
              std::string::npos)
        << e.what();
  }
}

TEST(SimTruth, MissingColumnsAndFilesAreNamed) {
  TempDir dir;
  WriteSimFolder(dir.path());
  std::ofstream(dir.path() / "truth" / "plants.csv") << "plant_id,class\n1,crop\n";
  EXPECT_THROW(LoadSimulatorTruth(dir.path()), DataError);
  fs::remove(dir.path() / "truth" / "visible_plants.csv");
  EXPECT_THROW(LoadSimulatorTruth(dir.path()), MapIoError);
  EXPECT_FALSE(IsSimulatorOutput(dir.path() / "truth"));
}

}  // namespace
}  // namespace plantscale::maps
