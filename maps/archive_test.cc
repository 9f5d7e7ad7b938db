// The season archive (archive.h) on a GeoPackage and on a real PostgreSQL +
// PostGIS server (test_pg_server.h; skipped with the reason when none starts).
#include "maps/archive.h"

#include <gdal_priv.h>
#include <gmock/gmock.h>
#include <ogrsf_frmts.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <thread>

#include "maps/archive_db.h"
#include "maps/map_errors.h"
#include "maps/test_maps.h"
#include "maps/test_pg_server.h"

namespace plantscale::maps {
namespace {

using testing::PgServer;
using testing::SyntheticMap;
using testing::TestAnchor;

ArchiveRun MakeRun(const std::string& id, const std::string& field, const std::string& start) {
  ArchiveRun r;
  r.run_id = id;
  r.field = field;
  r.bed = 4;
  r.vehicle = "vehicle-a";
  r.crop_profile = "lettuce";
  r.source = id + ".lcmlog";
  r.start_time = start;
  r.end_time = start;
  r.distance_m = 6.0;
  r.figures.crop = 30;
  r.figures.plants_per_m = 2.0;
  r.figures.rows.push_back({0, 10, 0.0, 4.5, 0.0, 2.0, 0, 0, 0.08, 1, 0.1});
  return r;
}

// The synthetic map seen again: every plant moved by `shift`, plant 5 gone
// (eaten), one new weed at (0.6, 1.3).
CropMap SecondVisit(const Eigen::Vector2d& shift) {
  const CropMap first = SyntheticMap();
  CropMap map(first.grid());
  map.MarkObserved({-1.0, -0.5}, {1.0, 5.5});
  for (MapPlant p : first.plants()) {
    if (p.id == 5) continue;
    p.position_m += shift;
    p.radius_m *= 1.5;  // grown
    map.AddPlant(p);
  }
  map.AddPlant({2000, {0.6, 1.3}, PlantKind::kWeed, 0.8, 0.02, true, "weed"});
  return map;
}

int64_t Count(const std::string& target, const std::string& sql) {
  ArchiveDb db = OpenArchive(target, false);
  return QueryInt(db, sql).value_or(-1);
}

// The season's contract on any target: match, replace, query, history.
void CheckSeason(const std::string& target, const std::string& field, const std::string& prefix = "") {
  const std::string run_a = prefix + "run-a", run_b = prefix + "run-b";
  const AppendResult a = AppendRun(target, MakeRun(run_a, field, "2026-05-01T08:00:00Z"), SyntheticMap(), TestAnchor());
  EXPECT_FALSE(a.replaced);
  EXPECT_EQ(a.plants, 32);
  EXPECT_EQ(a.new_plants, 32);
  // The second pass's frame 3 cm across and 8 cm along from the first: beyond
  // the 5 cm tolerance, found by the alignment; the field's stored frame is used.
  const AppendResult b = AppendRun(target, MakeRun(run_b, field, "2026-05-15T08:00:00Z"),
                                   SecondVisit({0.03, 0.08}), std::nullopt);
  EXPECT_EQ(b.matched, 31);
  EXPECT_EQ(b.new_plants, 1);
  EXPECT_NEAR(b.offset_m.x(), -0.03, 1e-9);
  EXPECT_NEAR(b.offset_m.y(), -0.08, 1e-9);
  // Re-export of run a: replaced, nothing duplicated.
  const AppendResult again = AppendRun(target, MakeRun(run_a, field, "2026-05-01T08:00:00Z"), SyntheticMap(), TestAnchor());
  EXPECT_TRUE(again.replaced);
  EXPECT_EQ(again.matched, 32);
  const std::string f = SqlLiteral(field);
  EXPECT_EQ(Count(target, "SELECT COUNT(*) FROM runs WHERE field = " + f), 2);
  EXPECT_EQ(Count(target, "SELECT COUNT(*) FROM plants WHERE field = " + f), 32 + 32);
  EXPECT_EQ(Count(target, "SELECT COUNT(*) FROM season_plants WHERE field = " + f), 33);
  EXPECT_EQ(Count(target, "SELECT COUNT(*) FROM rows WHERE field = " + f), 2);
  EXPECT_GE(Count(target, "SELECT COUNT(*) FROM treated_areas WHERE field = " + f), 2);
  EXPECT_GE(Count(target, "SELECT COUNT(*) FROM map_tiles WHERE field = " + f), 2);

  const std::vector<ArchivedRun> runs = QueryRuns(target, field);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].run_id, run_a);
  EXPECT_EQ(runs[1].run_id, run_b);
  EXPECT_EQ(runs[0].vehicle, "vehicle-a");
  EXPECT_EQ(runs[0].figures.treated_plants, 1);
  EXPECT_EQ(runs[1].figures.treated_plants, 2);
  EXPECT_GT(runs[0].figures.area_treated_m2, 0.0);
  EXPECT_EQ(QueryRuns(target, field, "2026-05-02").size(), 1u);
  EXPECT_EQ(QueryRuns(target, field, "", "2026-05-01").size(), 1u);
  EXPECT_EQ(QueryRuns(target, field, "2026-06-01").size(), 0u);

  // The weed sprayed in both runs: one season id, two sightings, treated twice.
  ArchiveDb db = OpenArchive(target, false);
  const int64_t weed = QueryInt(db, "SELECT season_id FROM plants WHERE field = " + f +
                                        " AND plant_id = 1000 AND run_id = " + SqlLiteral(run_b)).value();
  const PlantHistory h = QueryPlant(target, weed);
  EXPECT_EQ(h.field, field);
  EXPECT_EQ(h.cls, "weed");
  ASSERT_EQ(h.sightings.size(), 2u);
  EXPECT_EQ(h.sightings[0].run_id, run_a);
  EXPECT_EQ(h.times_treated, 2);
  EXPECT_NEAR(h.sightings[1].radius_m, 0.045, 1e-9);  // 0.03 grown by 1.5
  EXPECT_NEAR(h.field_x_m, 0.21, 1e-6);
}

TEST(ArchiveGpkg, MatchesReplacesAndQueries) {
  testing::TempDir dir;
  CheckSeason((dir.path() / "season.gpkg").string(), "north field");
}

TEST(ArchiveGpkg, RefusesARunOfNoPlantsAndANewFieldWithoutOrigin) {
  testing::TempDir dir;
  const std::string target = (dir.path() / "season.gpkg").string();
  CropMap empty(MapGrid({0.02, {0.0, 0.0}, 10, 10}));
  EXPECT_THROW(AppendRun(target, MakeRun("r", "f", ""), empty, TestAnchor()), InvalidOptionsError);
  EXPECT_THROW(AppendRun(target, MakeRun("r", "f", ""), SyntheticMap(), std::nullopt), InvalidOptionsError);
  EXPECT_THROW(QueryRuns((dir.path() / "none.gpkg").string(), "f"), MapIoError);
  EXPECT_THROW(QueryRuns(target, "f", "May 1st"), InvalidOptionsError);
}

TEST(ArchiveTarget, RedactsPasswords) {
  EXPECT_EQ(Redacted("postgresql://u:secret@h:5432/db"), "postgresql://u:***@h:5432/db");
  EXPECT_EQ(Redacted("PG:host=h password=secret dbname=d"), "PG:host=h password=*** dbname=d");
  EXPECT_EQ(SqlLiteral("a'b"), "'a''b'");
}

class ArchivePostgis : public ::testing::Test {
 protected:
  void SetUp() override {
    if (server_.url().empty()) GTEST_SKIP() << server_.skip_reason();
  }
  PgServer server_;
};

TEST_F(ArchivePostgis, MatchesReplacesAndQueries) {
  CheckSeason(server_.url(), "north field");
  // A field name holding quotes and SQL is data, not SQL.
  const std::string evil = "O'Brien's'; DROP TABLE runs; --";
  CheckSeason(server_.url(), evil, "evil-");
  EXPECT_EQ(QueryRuns(server_.url(), "north field").size(), 2u);
  testing::TempDir dir;
  const std::filesystem::path file = ExportSeason(server_.url(), evil, dir.path());
  GDALDatasetUniquePtr gpkg(GDALDataset::Open(file.c_str(), GDAL_OF_VECTOR));
  ASSERT_TRUE(gpkg);
  EXPECT_EQ(gpkg->GetLayerByName("runs")->GetFeatureCount(), 2);
  EXPECT_EQ(gpkg->GetLayerByName("season_plants")->GetFeatureCount(), 33);
  EXPECT_EQ(gpkg->GetLayerByName("plants")->GetFeatureCount(), 64);
}

TEST_F(ArchivePostgis, BadServersAreNamedAndChangeNothing) {
  const ArchiveRun run = MakeRun("r", "f", "2026-05-01T08:00:00Z");
  try {
    AppendRun(server_.Url("archive", "wrong"), run, SyntheticMap(), TestAnchor());
    FAIL() << "bad password accepted";
  } catch (const MapIoError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("password authentication failed"));
    EXPECT_THAT(e.what(), ::testing::Not(::testing::HasSubstr("wrong")));
  }
  try {
    AppendRun(server_.Url("plain"), run, SyntheticMap(), TestAnchor());
    FAIL() << "database without PostGIS accepted";
  } catch (const MapIoError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("no PostGIS"));
  }
  EXPECT_THROW(AppendRun("postgresql://plantscale:plantscale@127.0.0.1:1/archive", run, SyntheticMap(), TestAnchor()),
               MapIoError);
  EXPECT_THROW(QueryRuns(server_.url(), "f"), MapIoError);  // nothing was created: not an archive yet
}

// Two vehicles export runs of one field at once: both runs stored, the
// second matches the first's plants (no season plant twice).
TEST_F(ArchivePostgis, ConcurrentAppendsLoseAndDuplicateNothing) {
  const std::string url = server_.url();
  std::vector<std::thread> threads;
  std::vector<AppendResult> results(4);
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back([&, i] {
      ArchiveRun run = MakeRun("run-" + std::to_string(i), "field", "2026-05-0" + std::to_string(i + 1) + "T08:00:00Z");
      run.vehicle = "vehicle-" + std::to_string(i);
      results[static_cast<size_t>(i)] = AppendRun(url, run, SyntheticMap(), TestAnchor());
    });
  }
  for (std::thread& t : threads) t.join();
  int new_plants = 0;
  for (const AppendResult& r : results) new_plants += r.new_plants;
  EXPECT_EQ(new_plants, 32);  // exactly one export created them
  EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM runs"), 4);
  EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM season_plants"), 32);
  EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM plants"), 4 * 32);
  EXPECT_EQ(Count(url, "SELECT COUNT(DISTINCT season_id) FROM plants"), 32);
}

// A big run's export killed at 20 %, 50 % and 80 % of the time a whole
// export takes: the killed runs are absent, whole runs are whole, and no
// plant belongs to a run that is not there.
TEST_F(ArchivePostgis, KilledExportLeavesTheWholeRunOrNone) {
  CropMap big(MapGrid({0.02, {-1.0, -0.5}, 100, 20000}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-0.9, 0.9), y(0.0, 390.0);
  for (int64_t id = 1; id <= 60000; ++id) big.AddPlant({id, {x(rng), y(rng)}, PlantKind::kWeed, 0.9, 0.01, id % 3 == 0, "w"});
  const std::string url = server_.url();
  const auto t0 = std::chrono::steady_clock::now();
  AppendRun(url, MakeRun("whole", "field", "2026-05-01T08:00:00Z"), big, TestAnchor());
  const double whole_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  // Each kill leaves the run whole or absent. Under load an export may beat
  // its kill (it then must be whole); at least one must have been cut short.
  int killed = 0;
  for (double fraction : {0.2, 0.5, 0.8}) {
    const std::string id = "killed-" + std::to_string(static_cast<int>(100 * fraction));
    const pid_t child = fork();
    if (child == 0) {
      AppendRun(url, MakeRun(id, "field", "2026-05-02T08:00:00Z"), big, TestAnchor());
      _exit(0);
    }
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(fraction * whole_ms));
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    // A kill that lands after the COMMIT but before _exit finds the run
    // whole: "killed" is not "absent", so the run's presence is read, not
    // inferred from the signal.
    const int64_t runs = Count(url, "SELECT COUNT(*) FROM runs WHERE run_id = '" + id + "'");
    EXPECT_TRUE(runs == 0 || runs == 1) << id << ": " << runs << " runs";
    if (!WIFSIGNALED(status)) {
      EXPECT_EQ(runs, 1) << id << " finished but is absent";
    }
    EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM plants WHERE run_id = '" + id + "'"), 60000 * runs) << id;
    killed += runs == 0 ? 1 : 0;
  }
  EXPECT_GE(killed, 1) << "every export committed before its kill";
  EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM plants WHERE run_id = 'whole'"), 60000);
  EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM plants p WHERE NOT EXISTS (SELECT 1 FROM runs r WHERE r.run_id = p.run_id)"), 0);
  EXPECT_EQ(Count(url, "SELECT COUNT(*) FROM season_plants"), 60000);  // the killed runs matched, created nothing
}

}  // namespace
}  // namespace plantscale::maps
