#include "maps/crop_map.h"

#include <algorithm>
#include <cmath>

#include "engine/common/check.h"

namespace plantscale::maps {

const char* ToString(CellClass c) {
  switch (c) {
    case CellClass::kSoil:
      return "soil";
    case CellClass::kCrop:
      return "crop";
    case CellClass::kWeed:
      return "weed";
    case CellClass::kUnknown:
      return "unknown";
  }
  return "unknown";
}

const char* ToString(PlantKind k) {
  switch (k) {
    case PlantKind::kCrop:
      return "crop";
    case PlantKind::kWeed:
      return "weed";
    case PlantKind::kUnknown:
      return "unknown";
  }
  return "unknown";
}

PlantKind ParsePlantKind(const std::string& text, const std::string& what) {
  if (text == "crop") return PlantKind::kCrop;
  if (text == "weed") return PlantKind::kWeed;
  if (text == "unknown") return PlantKind::kUnknown;
  throw DataError(what + ": unknown plant class '" + text + "' (expected crop, weed, unknown)");
}

int Priority(CellClass c) {
  switch (c) {
    case CellClass::kUnknown:
      return 0;
    case CellClass::kSoil:
      return 1;
    case CellClass::kCrop:
      return 2;
    case CellClass::kWeed:
      return 3;
  }
  return 0;
}

CellClass ClassOf(PlantKind k) {
  if (k == PlantKind::kCrop) return CellClass::kCrop;
  if (k == PlantKind::kWeed) return CellClass::kWeed;
  return CellClass::kSoil;  // an unclassified plant still proves the cell was seen
}

CropMap::CropMap(const MapGrid& grid) : grid_(grid) {
  layers_.cls.assign(grid_.size(), static_cast<uint8_t>(CellClass::kUnknown));
  layers_.crop_count.assign(grid_.size(), 0);
  layers_.weed_count.assign(grid_.size(), 0);
  layers_.treated.assign(grid_.size(), 0);
}

CellClass CropMap::ClassAt(const Cell& cell) const {
  return static_cast<CellClass>(layers_.cls[grid_.Index(cell)]);
}

void CropMap::MarkObserved(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m) {
  for (size_t i = 0; i < grid_.size(); ++i) {
    const Eigen::Vector2d c = grid_.CellCentre(grid_.CellOf(i));
    const bool inside = (c.array() >= min_m.array()).all() && (c.array() <= max_m.array()).all();
    if (inside && layers_.cls[i] == static_cast<uint8_t>(CellClass::kUnknown)) {
      layers_.cls[i] = static_cast<uint8_t>(CellClass::kSoil);
    }
  }
}

template <typename F>
void CropMap::ForFootprint(const Eigen::Vector2d& centre_m, double radius_m, F&& f) {
  const double r = std::max(radius_m, 0.0);
  const Cell lo = grid_.CellAt(centre_m.array() - r);
  const Cell hi = grid_.CellAt(centre_m.array() + r);
  for (int row = std::max(lo.row, 0); row <= std::min(hi.row, grid_.rows() - 1); ++row) {
    for (int col = std::max(lo.col, 0); col <= std::min(hi.col, grid_.cols() - 1); ++col) {
      const Cell cell{col, row};
      if ((grid_.CellCentre(cell) - centre_m).norm() <= r) f(grid_.Index(cell));
    }
  }
  if (auto root = grid_.FindCell(centre_m)) f(grid_.Index(*root));  // tiny plants
}

void CropMap::AddPlant(const MapPlant& plant) {
  if (!plant.position_m.allFinite() || !std::isfinite(plant.radius_m)) {
    throw DataError("plant " + std::to_string(plant.id) + ": position or size is not finite");
  }
  if (plant_index_.count(plant.id) != 0) {
    throw DataError("plant " + std::to_string(plant.id) + ": duplicate id in the registry");
  }
  plant_index_[plant.id] = plants_.size();
  plants_.push_back(plant);
  if (auto root = grid_.FindCell(plant.position_m)) {
    const size_t i = grid_.Index(*root);
    auto bump = [](uint16_t& n) { n = static_cast<uint16_t>(std::min<int>(n + 1, kMaxCount)); };
    if (plant.kind == PlantKind::kCrop) bump(layers_.crop_count[i]);
    if (plant.kind == PlantKind::kWeed) bump(layers_.weed_count[i]);
  }
  const CellClass cls = ClassOf(plant.kind);
  ForFootprint(plant.position_m, plant.radius_m, [&](size_t i) {
    if (Priority(cls) > Priority(static_cast<CellClass>(layers_.cls[i]))) {
      layers_.cls[i] = static_cast<uint8_t>(cls);
    }
    if (plant.treated) layers_.treated[i] = 1;
  });
}

const MapPlant* CropMap::FindPlant(int64_t id) const {
  const auto it = plant_index_.find(id);
  return it == plant_index_.end() ? nullptr : &plants_[it->second];
}

void CropMap::SetLayers(MapLayers layers) {
  const size_t n = grid_.size();
  PLANTSCALE_CHECK(layers.cls.size() == n && layers.crop_count.size() == n &&
                       layers.weed_count.size() == n && layers.treated.size() == n,
                   "layer sizes differ from the grid");
  layers_ = std::move(layers);
}

void CropMap::SetPlants(std::vector<MapPlant> plants) {
  std::unordered_map<int64_t, size_t> index;
  for (size_t i = 0; i < plants.size(); ++i) {
    if (!index.emplace(plants[i].id, i).second) {
      throw DataError("plant " + std::to_string(plants[i].id) + ": duplicate id in the registry");
    }
  }
  plants_ = std::move(plants);
  plant_index_ = std::move(index);
}

size_t CropMap::treated_cells() const {
  return static_cast<size_t>(std::count(layers_.treated.begin(), layers_.treated.end(), 1));
}

}  // namespace plantscale::maps
