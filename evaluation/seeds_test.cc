#include "evaluation/seeds.h"

#include <gtest/gtest.h>

#include <sstream>
#include <vector>

#include "evaluation/rows_writer.h"
#include "evaluation/tracking_writer.h"
#include "evaluation/treatment_writer.h"
#include "evaluation/writer.h"

namespace plantscale::app {
namespace {

TEST(ForEachSeed, RunsSeedAfterSeedFromThePresetsWithItsOtherOptions) {
  sim::SimulatorOptions preset;
  preset.seed = 7;
  preset.length_m = 12.5;
  std::vector<int> indices;
  std::vector<uint64_t> seeds;
  ForEachSeed(preset, 3, [&](int k, sim::SimulatorOptions& options) {
    indices.push_back(k);
    seeds.push_back(options.seed);
    EXPECT_EQ(options.length_m, 12.5);
    options.length_m = 1.0;  // the run's own copy
  });
  EXPECT_EQ(indices, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(seeds, (std::vector<uint64_t>{7, 8, 9}));
  EXPECT_EQ(preset.length_m, 12.5);
  EXPECT_EQ(NthSeed(7, 2), 9u);
}

TEST(ForEachSeed, NoSeedsNoRun) {
  int runs = 0;
  ForEachSeed(sim::SimulatorOptions{}, 0, [&](int, sim::SimulatorOptions&) { ++runs; });
  EXPECT_EQ(runs, 0);
}

TEST(WriteEvaluation, JsonIsOneIndentedObjectOnALineOfItsOwn) {
  RowsEvaluation e;
  e.preset = "field";
  std::ostringstream json, table;
  WriteEvaluation(e, true, json);
  EXPECT_EQ(json.str(), ToJson(e).dump(2) + "\n");
  WriteEvaluation(e, false, table);
  EXPECT_EQ(table.str().rfind("preset field, 0 seed(s)", 0), 0u) << table.str();
}

TEST(WriteEvaluation, TrackingAndTreatmentNameTheEngineAlike) {
  TrackingEvaluation tracking;
  TreatmentEvaluation treatment;
  for (EngineUsed* engine : {&tracking.engine, &treatment.engine}) {
    engine->crop = "sugar_beet";
    engine->vehicle = "robot";
    engine->calibration_error_text = "height_m=0.01";
  }
  std::ostringstream a, b;
  WriteTable(tracking, a);
  WriteTable(treatment, b);
  const std::string line = "  engine: crop sugar_beet, vehicle robot, calibration error height_m=0.01\n";
  EXPECT_NE(a.str().find(line), std::string::npos) << a.str();
  EXPECT_NE(b.str().find(line), std::string::npos) << b.str();
  EXPECT_EQ(ToJson(tracking)["crop"], "sugar_beet");
  EXPECT_EQ(ToJson(treatment)["vehicle"], "robot");
}

TEST(WriteEvaluation, TreatmentNamesEachSeedOfItsRun) {
  TreatmentEvaluation e;
  e.first_seed = 3;
  e.seeds = 2;
  MissedCrop missed;
  missed.seed_index = 1;
  e.missed_crops.push_back(missed);
  const nlohmann::json j = ToJson(e);
  ASSERT_EQ(j["per_seed"].size(), 2u);
  EXPECT_EQ(j["per_seed"][0]["seed"], 3);
  EXPECT_EQ(j["per_seed"][1]["seed"], 4);
  EXPECT_EQ(j["missed_crops"][0]["seed"], 4);
}

TEST(WriteEvaluation, ShapesHoldEveryOptionalPart) {
  const nlohmann::json tracking = TrackingJsonShape();
  EXPECT_TRUE(tracking.contains("baseline_thesis"));
  EXPECT_TRUE(tracking.contains("odometry_fault"));
  EXPECT_EQ(tracking["reference"], "plant-lines");
  const nlohmann::json treatment = TreatmentJsonShape();
  EXPECT_TRUE(treatment.contains("mrroc"));
  EXPECT_TRUE(treatment["odometry_fault"].contains("stretch"));
  EXPECT_EQ(PhotoRowsJsonShape()["mask"], "model crop class");
}

}  // namespace
}  // namespace plantscale::app
