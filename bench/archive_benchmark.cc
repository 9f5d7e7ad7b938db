// The season archive (issue 37): a season of 50 runs of 1 km each imported
// into PostgreSQL + PostGIS (a throw-away server, tests/pg_server.sh), then
// `archive query` over it.
//
// The runs are made cheaply from one synthetic 1 km bed, the kind a run's
// log gives (app/log_map.h): lettuce, 3 rows 0.4 m apart, a plant every
// 0.3 m (10 000 crops), 2.5 weeds per m² (3 000), a 4 cm map grid with
// every plant's footprint painted and the weeds treated (coarser than the
// vehicle's 1.333 cm cells, which make a run's import raster-bound: a real
// 1 km field log's import is measured on its own, docs/results/
// 2026-11-27-archive.md). Run k moves every
// plant by N(0, 1 cm) (re-localisation), loses 1 % of the crops, grows them
// by 2 % and brings new weeds, so matching does the work it does on a farm;
// its run id and start date vary. Each run goes through what
// `plantscale export --to` does after reading the log: the agronomic figures
// (app/archive_run.h) and maps::AppendRun.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <random>
#include <string>
#include <sys/wait.h>

#include "app/archive_run.h"
#include "maps/archive.h"

namespace plantscale {
namespace {

constexpr int kRuns = 50;
constexpr double kLengthM = 1000.0;

struct Server {
  std::string dir = "/tmp/plantscale_archive_bench_" + std::to_string(getpid());
  std::string url;
  Server() {
    FILE* p = popen(("bash '" PLANTSCALE_PG_SERVER_SCRIPT "' start " + dir + " 2>&1").c_str(), "r");
    char buf[512];
    while (p != nullptr && fgets(buf, sizeof buf, p) != nullptr) url += buf;
    const int status = p != nullptr ? pclose(p) : -1;
    if (status != 0 || url.rfind("postgresql://", 0) != 0) url.clear();
    while (!url.empty() && url.back() == '\n') url.pop_back();
  }
  ~Server() { std::system(("bash '" PLANTSCALE_PG_SERVER_SCRIPT "' stop " + dir).c_str()); }
};

Server& TheServer() {
  static Server server;
  return server;
}

maps::CropMap Bed(int run) {
  std::mt19937 rng(static_cast<unsigned>(1000 + run));
  std::normal_distribution<double> jitter(0.0, 0.01);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  maps::CropMap map(maps::MapGrid::Covering({-0.8, -0.5}, {0.8, kLengthM + 0.5}, 0.04));
  map.MarkObserved({-0.8, -0.5}, {0.8, kLengthM + 0.5});
  int64_t id = 1;
  for (int n = -1; n <= 1; ++n) {
    for (int m = 0; m * 0.3 < kLengthM; ++m, ++id) {
      std::mt19937 plant_rng(static_cast<unsigned>(id));  // the same field every run
      if (std::uniform_real_distribution<double>(0, 1)(plant_rng) < 0.03) continue;  // never came up
      if (u(rng) < 0.01) continue;  // lost this week
      map.AddPlant({id, {0.4 * n + jitter(rng), 0.3 * m + jitter(rng)}, maps::PlantKind::kCrop, 0.9,
                    0.03 * (1.0 + 0.02 * run), false, "crop: in the association region"});
    }
  }
  std::mt19937 field_rng(7);
  std::uniform_real_distribution<double> wx(-0.6, 0.6), wy(0.0, kLengthM);
  for (int w = 0; w < 3000; ++w, ++id) {
    const Eigen::Vector2d p(wx(field_rng), wy(field_rng));
    map.AddPlant({id, p + Eigen::Vector2d(jitter(rng), jitter(rng)), maps::PlantKind::kWeed, 0.8, 0.012, true,
                  "weed: outside every association region"});
  }
  for (int w = 0; w < 100; ++w, ++id) {  // new this week
    map.AddPlant({id, {wx(rng), wy(rng)}, maps::PlantKind::kWeed, 0.8, 0.008, true, "weed: too small for a crop plant"});
  }
  return map;
}

maps::GeoAnchorOptions Anchor() {
  maps::GeoAnchorOptions a;
  a.latitude_deg = 52.0;
  a.longitude_deg = -0.4;
  a.heading_deg = 30.0;
  return a;
}

maps::AppendResult Import(const std::string& url, const std::string& field, int run, const maps::CropMap& map) {
  maps::ArchiveRun r = app::ArchiveRunFromMap("bench.psmap", map);
  r.run_id = "bench-" + std::to_string(run);
  r.field = field;
  r.bed = 1 + run % 2;
  r.vehicle = "bench";
  char date[32];
  std::snprintf(date, sizeof date, "2026-%02d-%02dT08:00:00Z", 3 + run / 28, 1 + run % 28);
  r.start_time = r.end_time = date;
  r.distance_m = kLengthM;
  return maps::AppendRun(url, r, map, Anchor());
}

// One iteration: a season of 50 runs into a fresh field; counter
// s_per_run = seconds per run imported.
void BM_ImportSeason(benchmark::State& state) {
  const std::string& url = TheServer().url;
  if (url.empty()) return state.SkipWithError("no PostgreSQL server (tests/pg_server.sh)");
  int season = 0;
  double matched = 0.0, seen_before = 0.0, new_plants = 0.0;
  for (auto _ : state) {
    const std::string field = "season-" + std::to_string(season++);
    for (int k = 0; k < kRuns; ++k) {
      state.PauseTiming();  // making the run's map is not importing it (and 50 maps do not fit in memory)
      const maps::CropMap map = Bed(k);
      state.ResumeTiming();
      const maps::AppendResult r = Import(url, field, k, map);
      if (k == 0) continue;
      matched += r.matched;
      new_plants += r.new_plants;
      seen_before += r.plants - 100;  // all but the week's new weeds stand where a plant stood
    }
  }
  // Share of the plants of runs 2..50 that kept a season id (all should
  // but the ones beyond 5 cm: N(0, 1 cm) per run per axis).
  state.counters["matched_share"] = matched / seen_before;
  state.counters["new_per_run"] = new_plants / (season * (kRuns - 1));
  state.counters["s_per_run"] = benchmark::Counter(static_cast<double>(kRuns * season), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_ImportSeason)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// `archive query` of the season imported above (all 50 runs, then a month).
void BM_QuerySeason(benchmark::State& state) {
  const std::string& url = TheServer().url;
  if (url.empty()) return state.SkipWithError("no PostgreSQL server (tests/pg_server.sh)");
  size_t runs = 0;
  for (auto _ : state) {
    runs = maps::QueryRuns(url, "season-0").size();
    benchmark::DoNotOptimize(maps::QueryRuns(url, "season-0", "2026-03-01", "2026-03-28").size());
  }
  if (runs != kRuns) state.SkipWithError(("expected 50 runs, found " + std::to_string(runs)).c_str());
  state.counters["runs"] = static_cast<double>(runs);
}
BENCHMARK(BM_QuerySeason)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace plantscale

BENCHMARK_MAIN();
