#include "app/log_map.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>

#include "review/synthetic_run.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/log.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;
namespace ch = telemetry::channels;

fs::path Temp(const std::string& name) {
  return fs::temp_directory_path() / ("plantscale_logmap_" + std::to_string(::getpid()) + "_" + name);
}

// What the log says, decoded here independently of CropMapFromLog.
struct Expected {
  std::map<int64_t, plantscale_plant_t> plants;  // newest per id
  int tiles = 0;
};

Expected Decode(const std::vector<telemetry::LogEvent>& events) {
  Expected x;
  std::map<std::pair<int, int>, int> tiles;
  for (const auto& e : events) {
    if (e.channel == ch::kPlants) {
      const auto list = telemetry::Decode<plantscale_plant_list_t>(e.channel, e.data.data(), e.data.size());
      for (const auto& p : list->plants) x.plants[p.id] = p;
    } else if (e.channel == ch::kMapTiles) {
      const auto t = telemetry::Decode<plantscale_map_tile_t>(e.channel, e.data.data(), e.data.size());
      tiles[{t->tile_x, t->tile_y}] = 1;
    }
  }
  x.tiles = static_cast<int>(tiles.size());
  return x;
}

TEST(LogMap, EveryPlantAndTileOfARunLandsInTheMap) {
  review::SyntheticRunOptions o;
  o.length_m = 8.0;
  const fs::path log = Temp("run.lcmlog");
  review::WriteSyntheticLog(log, o);
  const Expected x = Decode(review::SyntheticRun(o));
  ASSERT_GT(x.plants.size(), 40u);
  ASSERT_GT(x.tiles, 0);

  LogMapReport report;
  int64_t last_done = -1, last_total = -1;
  const maps::CropMap map = CropMapFromLog(log, report, [&](int64_t d, int64_t t) { last_done = d, last_total = t; });
  EXPECT_EQ(report.tiles, x.tiles);
  EXPECT_EQ(report.bad_messages, 0);
  EXPECT_TRUE(report.problems.empty());
  EXPECT_EQ(last_done, last_total);
  EXPECT_EQ(last_done, report.events);
  ASSERT_EQ(map.plants().size(), x.plants.size());
  int crop = 0, treated = 0;
  for (const auto& [id, p] : x.plants) {
    const maps::MapPlant* m = map.FindPlant(id);
    ASSERT_NE(m, nullptr) << id;
    EXPECT_NEAR(m->position_m.x(), p.position_m[0], 1e-12);
    EXPECT_NEAR(m->position_m.y(), p.position_m[1], 1e-12);
    EXPECT_EQ(m->treated, p.sprayed != 0);
    EXPECT_EQ(m->kind == maps::PlantKind::kCrop, p.cls == plantscale_plant_t::CLS_CROP);
    crop += p.cls == plantscale_plant_t::CLS_CROP;
    treated += p.sprayed != 0;
    // The plant's root cell is painted with a plant class (its own or a weed over it).
    const maps::CellClass c = map.ClassAt(map.grid().CellAt(m->position_m));
    EXPECT_TRUE(c == maps::CellClass::kCrop || c == maps::CellClass::kWeed) << id;
  }
  // Three rows at 0.45 m over the 8 m driven plus the camera's view ahead.
  EXPECT_GT(crop, 3 * 8.0 / 0.45 - 3);
  EXPECT_EQ(map.grid().resolution_m(), o.cell_m);
  ASSERT_GT(treated, 0);
  EXPECT_GT(map.treated_cells(), 0u);
  EXPECT_EQ(map.metadata().at("source"), "lcm log");
  fs::remove(log);
}

TEST(LogMap, ACutOffLogGivesTheMapUpToItsLastWholeEvent) {
  review::SyntheticRunOptions o;
  o.length_m = 4.0;
  const fs::path log = Temp("cut.lcmlog");
  review::WriteSyntheticLog(log, o);
  fs::resize_file(log, fs::file_size(log) - 7);
  LogMapReport report;
  const maps::CropMap map = CropMapFromLog(log, report);
  EXPECT_GT(map.plants().size(), 10u);
  ASSERT_EQ(report.problems.size(), 1u);
  EXPECT_NE(report.problems[0].find("byte offset"), std::string::npos) << report.problems[0];
  fs::remove(log);
}

TEST(LogMap, NotALogAndALogWithoutMapsAreClearErrors) {
  const fs::path text = Temp("text.lcmlog");
  std::ofstream(text) << "not a log\n";
  LogMapReport report;
  EXPECT_THROW(CropMapFromLog(text, report), telemetry::LogError);
  EXPECT_THROW(CropMapFromLog(Temp("missing.lcmlog"), report), telemetry::LogError);

  const fs::path grid_only = Temp("grid.lcmlog");
  {
    telemetry::LogWriter w(grid_only);
    const uint8_t junk[3] = {1, 2, 3};
    w.Write(ch::kGrid, junk, sizeof junk, 1);
  }
  try {
    CropMapFromLog(grid_only, report);
    ADD_FAILURE() << "no throw";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("nothing to map"), std::string::npos) << e.what();
  }
  fs::remove(text);
  fs::remove(grid_only);
}

TEST(LogMap, AMalformedTileIsCountedAndSkipped) {
  review::SyntheticRunOptions o;
  o.length_m = 3.0;
  const fs::path log = Temp("bad.lcmlog");
  {
    telemetry::LogWriter w(log);
    for (const auto& e : review::SyntheticRun(o)) w.Write(e.channel, e.data.data(), e.data.size(), e.utime);
    const uint8_t junk[5] = {9, 9, 9, 9, 9};
    w.Write(ch::kMapTiles, junk, sizeof junk, o.start_utime + 10'000'000);
  }
  LogMapReport report;
  const maps::CropMap map = CropMapFromLog(log, report);
  EXPECT_EQ(report.bad_messages, 1);
  ASSERT_EQ(report.problems.size(), 1u);
  EXPECT_NE(report.problems[0].find(ch::kMapTiles), std::string::npos) << report.problems[0];
  EXPECT_GT(map.plants().size(), 5u);
  fs::remove(log);
}

}  // namespace
}  // namespace plantscale::app
