#include "app/treatment_map_export.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace plantscale::app {

maps::CropMap ToCropMap(const treatment::TreatmentMap& map,
                        const treatment::PlantRegistry& registry) {
  maps::MapGridOptions g;
  g.resolution_m = map.options().cell_m;
  g.origin_m = {map.origin_x_m(), map.options().start_y_m};
  g.cols = map.columns();
  g.rows = std::max(1, map.rows());
  maps::CropMap out{maps::MapGrid(g)};
  maps::MapLayers layers;
  const size_t n = static_cast<size_t>(g.cols) * static_cast<size_t>(g.rows);
  layers.cls.assign(n, static_cast<uint8_t>(maps::CellClass::kSoil));
  layers.crop_count.assign(n, 0);
  layers.weed_count.assign(n, 0);
  layers.treated.assign(n, 0);
  for (int r = 0; r < map.rows(); ++r) {
    for (int c = 0; c < map.columns(); ++c) {
      const treatment::CellClass k = map.ClassOf(c, r);
      const size_t i = static_cast<size_t>(r) * static_cast<size_t>(g.cols) + static_cast<size_t>(c);
      if (k == treatment::CellClass::kCrop) layers.cls[i] = static_cast<uint8_t>(maps::CellClass::kCrop);
      if (k == treatment::CellClass::kWeed) layers.cls[i] = static_cast<uint8_t>(maps::CellClass::kWeed);
    }
  }
  out.SetLayers(std::move(layers));
  for (const treatment::PlantRecord& r : registry.records()) {
    maps::MapPlant p;
    p.id = r.id;
    p.position_m = r.bed_m;
    p.kind = r.crop() ? maps::PlantKind::kCrop : maps::PlantKind::kWeed;
    const int votes = r.crop_votes + r.weed_votes;
    p.confidence = votes > 0 ? static_cast<double>(std::max(r.crop_votes, r.weed_votes)) / votes : 0.0;
    p.radius_m = std::sqrt(r.area_m2 / std::numbers::pi);
    p.treated = r.sprayed;
    p.why = r.why;
    out.AddPlant(p);
  }
  out.SetMetadata("source", "plantscale treatment map (bed frame)");
  return out;
}

}  // namespace plantscale::app
