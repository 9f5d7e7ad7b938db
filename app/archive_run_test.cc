#include "app/archive_run.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include "app/log_map.h"
#include "review/synthetic_run.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

fs::path Temp(const std::string& name) {
  return fs::temp_directory_path() / ("plantscale_archrun_" + std::to_string(::getpid()) + "_" + name);
}

review::SyntheticRunOptions Bed(uint32_t seed) {
  review::SyntheticRunOptions o;
  o.length_m = 12.0;
  o.seed = seed;
  o.missing_crops = {{0, 6}, {0, 7}, {1, 10}};  // two gaps: one of 2 plants, one of 1
  return o;
}

TEST(ArchiveRun, ALogGivesItsIdTimesAndFigures) {
  const fs::path log = Temp("a.lcmlog"), other = Temp("b.lcmlog");
  review::WriteSyntheticLog(log, Bed(1));
  review::WriteSyntheticLog(other, Bed(2));
  const maps::ArchiveRun run = ArchiveRunFromLog(log);
  EXPECT_EQ(run.run_id.size(), 16u);
  EXPECT_EQ(run.run_id, RunIdOf(log));           // the same log, the same run
  EXPECT_NE(run.run_id, RunIdOf(other));         // another run, another id
  EXPECT_EQ(run.start_time, "2023-11-14T22:13:20Z");  // start_utime 1 700 000 000 s
  EXPECT_GT(run.end_time, run.start_time);
  EXPECT_NEAR(run.distance_m, 12.0, 0.5);
  EXPECT_EQ(run.figures.gaps, 2);
  EXPECT_EQ(run.figures.missing, 3);
  ASSERT_EQ(run.figures.rows.size(), 3u);
  // Crops every 0.45 m: plants per metre of stand 1 / 0.45 less the missing ones.
  EXPECT_NEAR(run.figures.plants_per_m, 1.0 / 0.45, 0.15);

  // The same run read as a map: the same gaps from the map's plants alone.
  LogMapReport report;
  const maps::CropMap map = CropMapFromLog(log, report);
  const maps::ArchiveRun from_map = ArchiveRunFromMap(log, map);
  EXPECT_EQ(from_map.figures.gaps, 2);
  EXPECT_EQ(from_map.figures.missing, 3);
  EXPECT_EQ(from_map.figures.crop, run.figures.crop);
  EXPECT_NEAR(from_map.figures.median_radius_m, run.figures.median_radius_m, 1e-9);
  EXPECT_TRUE(from_map.start_time.empty());
  fs::remove(log);
  fs::remove(other);
}

}  // namespace
}  // namespace plantscale::app
