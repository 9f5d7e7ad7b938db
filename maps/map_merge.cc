#include "maps/map_merge.h"

#include <algorithm>
#include <cmath>

namespace plantscale::maps {
namespace {

void CheckAligned(const MapGrid& a, const MapGrid& b, size_t index) {
  const std::string which = "merge: map " + std::to_string(index + 1);
  if (std::abs(a.resolution_m() - b.resolution_m()) > 1e-12) {
    throw DataError(which + " has cells of " + std::to_string(b.resolution_m()) +
                    " m, the first map " + std::to_string(a.resolution_m()) + " m");
  }
  const Eigen::Vector2d shift = (b.origin_m() - a.origin_m()) / a.resolution_m();
  if ((shift.array() - shift.array().round()).abs().maxCoeff() > 1e-6) {
    throw DataError(which + ": grid is not aligned with the first map's on whole cells");
  }
}

MapGrid UnionGrid(const std::vector<CropMap>& maps) {
  Eigen::Vector2d lo = maps[0].grid().origin_m();
  Eigen::Vector2d hi = maps[0].grid().max_m();
  for (const CropMap& m : maps) {
    lo = lo.cwiseMin(m.grid().origin_m());
    hi = hi.cwiseMax(m.grid().max_m());
  }
  const double res = maps[0].grid().resolution_m();
  MapGridOptions o;
  o.resolution_m = res;
  o.origin_m = lo;
  o.cols = static_cast<int>(std::lround((hi.x() - lo.x()) / res));
  o.rows = static_cast<int>(std::lround((hi.y() - lo.y()) / res));
  return MapGrid(o);
}

void AddLayers(const CropMap& from, const MapGrid& grid, MapLayers& into) {
  const MapGrid& g = from.grid();
  const MapLayers& l = from.layers();
  const Eigen::Vector2d shift = (g.origin_m() - grid.origin_m()) / grid.resolution_m();
  const int dc = static_cast<int>(std::lround(shift.x()));
  const int dr = static_cast<int>(std::lround(shift.y()));
  auto add = [](uint16_t a, uint16_t b) {
    return static_cast<uint16_t>(std::min<int>(a + b, CropMap::kMaxCount));
  };
  for (size_t i = 0; i < g.size(); ++i) {
    const Cell c = g.CellOf(i);
    const size_t j = grid.Index({c.col + dc, c.row + dr});
    if (Priority(static_cast<CellClass>(l.cls[i])) >
        Priority(static_cast<CellClass>(into.cls[j]))) {
      into.cls[j] = l.cls[i];
    }
    into.crop_count[j] = add(into.crop_count[j], l.crop_count[i]);
    into.weed_count[j] = add(into.weed_count[j], l.weed_count[i]);
    into.treated[j] = static_cast<uint8_t>(into.treated[j] | l.treated[i]);
  }
}

class Registry {
 public:
  explicit Registry(double distance_m) : distance_m_(distance_m) {}

  void Add(const MapPlant& p) {
    MapPlant* same = Match(p);
    if (same != nullptr) {
      same->confidence = std::max(same->confidence, p.confidence);
      if (p.treated && !same->treated) same->why = p.why;
      same->treated = same->treated || p.treated;
      return;
    }
    MapPlant copy = p;
    if (std::any_of(plants_.begin(), plants_.end(),
                    [&](const MapPlant& q) { return q.id == p.id; })) {
      copy.id = max_id_ + 1;
    }
    max_id_ = std::max(max_id_, copy.id);
    plants_.push_back(copy);
  }
  std::vector<MapPlant> Take() { return std::move(plants_); }

 private:
  MapPlant* Match(const MapPlant& p) {
    MapPlant* nearest = nullptr;
    double best = distance_m_;
    for (MapPlant& q : plants_) {
      if (q.kind != p.kind) continue;
      const double d = (q.position_m - p.position_m).norm();
      if (q.id == p.id && d <= distance_m_) return &q;
      if (d <= best) {
        best = d;
        nearest = &q;
      }
    }
    return nearest;
  }

  double distance_m_;
  int64_t max_id_ = 0;
  std::vector<MapPlant> plants_;
};

}  // namespace

OptionErrors MergeOptions::Validate() const {
  OptionErrors errors;
  RequireNonNegative(errors, "same_plant_distance_m", same_plant_distance_m);
  return errors;
}

CropMap MergeMaps(const std::vector<CropMap>& maps, const MergeOptions& options) {
  ThrowIfInvalid("merge options", options.Validate());
  if (maps.empty()) throw DataError("merge: no maps given");
  for (size_t i = 1; i < maps.size(); ++i) CheckAligned(maps[0].grid(), maps[i].grid(), i);
  CropMap merged(UnionGrid(maps));
  MapLayers layers = merged.layers();
  Registry registry(options.same_plant_distance_m);
  for (const CropMap& m : maps) {
    AddLayers(m, merged.grid(), layers);
    for (const MapPlant& p : m.plants()) registry.Add(p);
  }
  merged.SetLayers(std::move(layers));
  merged.SetPlants(registry.Take());
  for (const MapRow& r : maps[0].rows()) merged.AddRow(r);
  for (const auto& [k, v] : maps[0].metadata()) merged.SetMetadata(k, v);
  std::string sources;
  for (const CropMap& m : maps) {
    const auto it = m.metadata().find("source");
    sources += (sources.empty() ? "" : "; ") + (it != m.metadata().end() ? it->second : "?");
  }
  merged.SetMetadata("merged_from", std::to_string(maps.size()) + " maps: " + sources);
  return merged;
}

}  // namespace plantscale::maps
