#include "maps/sim_truth.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "maps/csv_table.h"
#include "maps/map_errors.h"

namespace plantscale::maps {
namespace fs = std::filesystem;
namespace {

struct TruthPlant {
  MapPlant plant;
  int row = 0;
};

size_t SizeOf(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  return ec ? 0 : static_cast<size_t>(size);
}

std::set<int64_t> SeenIds(const fs::path& file, size_t offset, size_t total,
                          const ReadProgress& progress) {
  CsvReader csv(file, {"plant_id"});
  std::set<int64_t> ids;
  while (csv.Next()) {
    ids.insert(csv.Integer("plant_id"));
    if (progress && csv.line() % 4096 == 0) progress(offset + csv.bytes_read(), total);
  }
  return ids;
}

std::vector<TruthPlant> SeenPlants(const fs::path& file, const std::set<int64_t>& seen) {
  CsvReader csv(file, {"plant_id", "class", "row", "x_m", "y_m", "radius_m"});
  std::vector<TruthPlant> plants;
  while (csv.Next()) {
    TruthPlant t;
    t.plant.id = csv.Integer("plant_id");
    if (seen.count(t.plant.id) == 0) continue;
    const std::string where = file.string() + ": line " + std::to_string(csv.line());
    t.plant.kind = ParsePlantKind(csv.Text("class"), where);
    t.plant.position_m = {csv.Number("x_m"), csv.Number("y_m")};
    t.plant.radius_m = csv.Number("radius_m");
    t.plant.confidence = 1.0;
    t.plant.treated = t.plant.kind == PlantKind::kWeed;
    t.plant.why = t.plant.treated ? "simulator truth: weed, ideal treatment" : "crop";
    t.row = static_cast<int>(csv.Integer("row"));
    plants.push_back(t);
  }
  return plants;
}

// Row n follows x = n·r̄(y) through the plant lines inside the map.
std::vector<MapRow> Rows(const fs::path& file, const std::set<int>& row_ids, const MapGrid& g) {
  CsvReader csv(file, {"y_m", "row_spacing_m"});
  std::map<int, MapRow> rows;
  while (csv.Next()) {
    const double y = csv.Number("y_m");
    if (y < g.origin_m().y() || y > g.max_m().y()) continue;
    for (int n : row_ids) {
      rows[n].index = n;
      rows[n].points_m.emplace_back(n * csv.Number("row_spacing_m"), y);
    }
  }
  std::vector<MapRow> out;
  for (auto& [n, r] : rows) {
    if (r.points_m.size() >= 2) out.push_back(std::move(r));
  }
  return out;
}

void AddRunMetadata(const fs::path& dir, CropMap& map) {
  map.SetMetadata("source", "simulator truth");
  map.SetMetadata("source_path", fs::absolute(dir).string());
  const fs::path run_file = dir / "run.json";
  std::ifstream in(run_file);
  if (!in) return;  // optional
  try {
    const nlohmann::json run = nlohmann::json::parse(in);
    for (const char* key : {"preset", "seed", "length_m", "frames"}) {
      if (run.contains(key)) {
        const auto& v = run.at(key);
        map.SetMetadata(key, v.is_string() ? v.get<std::string>() : v.dump());
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw DataError(run_file.string() + ": malformed JSON: " + e.what());
  }
}

}  // namespace

OptionErrors SimTruthOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "resolution_m", resolution_m);
  RequireNonNegative(errors, "margin_m", margin_m);
  return errors;
}

bool IsSimulatorOutput(const fs::path& dir) {
  return fs::is_directory(dir) && fs::is_regular_file(dir / "truth" / "plants.csv");
}

CropMap LoadSimulatorTruth(const fs::path& dir, const SimTruthOptions& options,
                           const ReadProgress& progress) {
  ThrowIfInvalid("simulator truth map", options.Validate());
  const fs::path truth = dir / "truth";
  const size_t total = SizeOf(truth / "visible_plants.csv") + SizeOf(truth / "plants.csv");
  const std::set<int64_t> seen = SeenIds(truth / "visible_plants.csv", 0, total, progress);
  const std::vector<TruthPlant> plants = SeenPlants(truth / "plants.csv", seen);
  if (plants.empty()) throw DataError(truth.string() + ": the camera saw no plants; empty map");
  Eigen::Vector2d lo = plants[0].plant.position_m;
  Eigen::Vector2d hi = lo;
  std::set<int> row_ids;
  for (const TruthPlant& t : plants) {
    const Eigen::Vector2d r = Eigen::Vector2d::Constant(t.plant.radius_m);
    lo = lo.cwiseMin(t.plant.position_m - r);
    hi = hi.cwiseMax(t.plant.position_m + r);
    if (t.plant.kind == PlantKind::kCrop) row_ids.insert(t.row);
  }
  lo.array() -= options.margin_m;
  hi.array() += options.margin_m;
  CropMap map(MapGrid::Covering(lo, hi, options.resolution_m));
  map.MarkObserved(lo, hi);
  for (const TruthPlant& t : plants) map.AddPlant(t.plant);
  for (MapRow& r : Rows(truth / "lines.csv", row_ids, map.grid())) map.AddRow(std::move(r));
  AddRunMetadata(dir, map);
  if (progress) progress(total, total);
  return map;
}

}  // namespace plantscale::maps
