#include "app/log_map.h"

#include <plantscale_lcmtypes/plantscale_map_tile_t.hpp>
#include <plantscale_lcmtypes/plantscale_plant_list_t.hpp>

#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

#include "engine/common/options.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/log.h"

namespace plantscale::app {
namespace {

namespace ch = telemetry::channels;
using telemetry::MapTileDelta;
using telemetry::PlantObservation;

maps::PlantKind KindOf(telemetry::PlantKind k) {
  switch (k) {
    case telemetry::PlantKind::kCrop: return maps::PlantKind::kCrop;
    case telemetry::PlantKind::kWeed: return maps::PlantKind::kWeed;
    default: return maps::PlantKind::kUnknown;
  }
}

std::string WhyText(int why) {
  switch (why) {
    case plantscale_plant_t::WHY_CROP_IN_REGION: return "crop: in the association region";
    case plantscale_plant_t::WHY_OUTSIDE_REGION: return "weed: outside every association region";
    case plantscale_plant_t::WHY_TOO_SMALL: return "weed: too small for a crop plant";
    case plantscale_plant_t::WHY_TOO_LARGE: return "not crop: too large";
    case plantscale_plant_t::WHY_FAILSAFE: return "not sprayed: fail-safe";
    case plantscale_plant_t::WHY_MODE: return "not sprayed: treatment mode";
    case plantscale_plant_t::WHY_NOT_REACHED: return "not sprayed: the run ended before the bar reached it";
    case plantscale_plant_t::WHY_LEARNED: return "the grower's learned model's class";
    default: return "undecided";
  }
}

// What the tiles and plant lists of a log say, before the grid is known.
struct Collected {
  std::map<std::pair<int, int>, MapTileDelta> tiles;  // newest revision of each tile
  std::map<int64_t, PlantObservation> plants;         // newest observation of each id
};

void Take(const telemetry::LogEvent& e, Collected& c, LogMapReport& report) {
  std::string error;
  try {
    if (e.channel == ch::kMapTiles) {
      const auto m = telemetry::Decode<plantscale_map_tile_t>(e.channel, e.data.data(), e.data.size(), &error);
      if (!m) throw DataError(error);
      MapTileDelta t = telemetry::FromLcm(*m);
      auto [it, fresh] = c.tiles.try_emplace({t.tile_x, t.tile_y}, t);
      if (!fresh && t.revision >= it->second.revision) it->second = std::move(t);
    } else if (e.channel == ch::kPlants) {
      const auto m = telemetry::Decode<plantscale_plant_list_t>(e.channel, e.data.data(), e.data.size(), &error);
      if (!m) throw DataError(error);
      for (const plantscale_plant_t& p : m->plants) {
        PlantObservation o = telemetry::FromLcm(p);
        if (!o.position_m.allFinite()) throw DataError("plant " + std::to_string(p.id) + ": non-finite position");
        c.plants[o.id] = o;
      }
    }
  } catch (const std::exception& ex) {
    ++report.bad_messages;
    if (report.problems.size() < 20) {
      report.problems.push_back("event " + std::to_string(e.eventnum) + " on " + e.channel + ": " + ex.what());
    }
  }
}

maps::CellClass ClassOfCell(uint8_t cell) {
  switch (cell) {
    case plantscale_map_tile_t::CELL_SOIL:
    case plantscale_map_tile_t::CELL_TREATED: return maps::CellClass::kSoil;
    case plantscale_map_tile_t::CELL_CROP: return maps::CellClass::kCrop;
    case plantscale_map_tile_t::CELL_WEED: return maps::CellClass::kWeed;
    default: return maps::CellClass::kUnknown;
  }
}

maps::CropMap Assemble(const Collected& c, const std::filesystem::path& log) {
  double resolution = 0.0;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& [id, t] : c.tiles) {
    if (resolution == 0.0) resolution = t.resolution_m;
    if (std::abs(t.resolution_m - resolution) > 1e-9 * resolution) {
      throw DataError(log.string() + ": map tiles of two resolutions (" + std::to_string(resolution) + " and " +
                      std::to_string(t.resolution_m) + " m)");
    }
    lo = lo.cwiseMin(t.origin_m);
    hi = hi.cwiseMax(t.origin_m + resolution * Eigen::Vector2d(t.width - 0.5, t.height - 0.5));
  }
  if (resolution == 0.0) resolution = 0.01333;  // plants only: the treatment map's default cell
  for (const auto& [id, p] : c.plants) {
    const double r = std::sqrt(std::max(p.size_m2, 0.0) / std::numbers::pi);
    lo = lo.cwiseMin(p.position_m - Eigen::Vector2d::Constant(r));
    hi = hi.cwiseMax(p.position_m + Eigen::Vector2d::Constant(r));
  }
  maps::CropMap map(maps::MapGrid::Covering(lo, hi, resolution));
  const maps::MapGrid& g = map.grid();
  maps::MapLayers layers = map.layers();
  for (const auto& [id, t] : c.tiles) {
    for (int row = 0; row < t.height; ++row) {
      for (int col = 0; col < t.width; ++col) {
        const Eigen::Vector2d centre = t.origin_m + resolution * Eigen::Vector2d(col + 0.5, row + 0.5);
        const auto cell = g.FindCell(centre);
        if (!cell) continue;
        const uint8_t v = t.cells[static_cast<size_t>(row) * static_cast<size_t>(t.width) + static_cast<size_t>(col)];
        const size_t i = g.Index(*cell);
        layers.cls[i] = static_cast<uint8_t>(ClassOfCell(v));
        if (v == plantscale_map_tile_t::CELL_TREATED) layers.treated[i] = 1;
      }
    }
  }
  map.SetLayers(std::move(layers));
  for (const auto& [id, p] : c.plants) {
    maps::MapPlant mp;
    mp.id = p.id;
    mp.position_m = p.position_m;
    mp.kind = KindOf(p.kind);
    mp.radius_m = std::sqrt(std::max(p.size_m2, 0.0) / std::numbers::pi);
    mp.treated = p.sprayed;
    mp.why = WhyText(p.why);
    map.AddPlant(mp);
  }
  return map;
}

}  // namespace

maps::CropMap CropMapFromLog(const std::filesystem::path& log, LogMapReport& report,
                             const LogProgress& progress) {
  report = {};
  int64_t total = 0;
  {
    telemetry::LogReader counter(log);
    while (counter.Next()) ++total;
    if (total == 0) {
      throw telemetry::LogError(log.string() + ": no LCM events" +
                                (counter.error().empty() ? std::string() : " (" + counter.error() + ")"));
    }
  }
  telemetry::LogReader reader(log);
  Collected c;
  while (auto e = reader.Next()) {
    ++report.events;
    Take(*e, c, report);
    if (progress && report.events % 256 == 0) progress(report.events, total);
  }
  if (progress) progress(report.events, total);
  if (!reader.error().empty()) report.problems.push_back(reader.error() + " (read up to the last whole event)");
  if (c.tiles.empty() && c.plants.empty()) {
    throw DataError(log.string() + ": no map tiles (" + ch::kMapTiles + ") and no plants (" + ch::kPlants +
                    ") in " + std::to_string(report.events) + " events: nothing to map");
  }
  report.tiles = static_cast<int>(c.tiles.size());
  report.plants = static_cast<int>(c.plants.size());
  maps::CropMap map = Assemble(c, log);
  map.SetMetadata("source", "lcm log");
  map.SetMetadata("log", log.filename().string());
  map.SetMetadata("log_events", std::to_string(report.events));
  map.SetMetadata("map_tiles", std::to_string(report.tiles));
  if (report.bad_messages > 0) map.SetMetadata("bad_messages", std::to_string(report.bad_messages));
  return map;
}

}  // namespace plantscale::app
