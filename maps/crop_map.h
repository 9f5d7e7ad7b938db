#pragma once
// CropMap: what one or more passes over a bed found, in the field frame.
// Raster layers on a MapGrid (class, crop counts, weed counts, treated) and
// a registry of the plants themselves, plus the crop rows as lines and free
// text metadata about where the map came from (source, preset, seed, ...).

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/map_grid.h"

namespace plantscale::maps {

// Class of a cell. Unknown: never observed (exported as nodata).
enum class CellClass : uint8_t { kSoil = 0, kCrop = 1, kWeed = 2, kUnknown = 3 };
enum class PlantKind : uint8_t { kCrop = 1, kWeed = 2, kUnknown = 3 };
const char* ToString(CellClass c);
const char* ToString(PlantKind k);
// Throws DataError naming `what` for anything but crop, weed or unknown.
PlantKind ParsePlantKind(const std::string& text, const std::string& what);

struct MapPlant {
  int64_t id = 0;
  Eigen::Vector2d position_m{0.0, 0.0};  // root, field frame
  PlantKind kind = PlantKind::kUnknown;
  double confidence = 1.0;  // of the class, [0, 1]
  double radius_m = 0.0;    // size: outline radius at the leaf tips
  bool treated = false;
  std::string why;  // reason of the treatment decision (or of not treating)
};

struct MapRow {
  int index = 0;                          // row n of the bed (0: central row)
  std::vector<Eigen::Vector2d> points_m;  // along the row, field frame
};

struct MapLayers {
  std::vector<uint8_t> cls;          // CellClass
  std::vector<uint16_t> crop_count;  // crop roots in the cell (saturates)
  std::vector<uint16_t> weed_count;  // weed roots in the cell (saturates)
  std::vector<uint8_t> treated;      // 1: sprayed
};

class CropMap {
 public:
  static constexpr uint16_t kMaxCount = 65534;  // 65535 is the export nodata

  explicit CropMap(const MapGrid& grid);

  const MapGrid& grid() const { return grid_; }
  const MapLayers& layers() const { return layers_; }
  const std::vector<MapPlant>& plants() const { return plants_; }
  const std::vector<MapRow>& rows() const { return rows_; }
  const std::map<std::string, std::string>& metadata() const { return metadata_; }

  CellClass ClassAt(const Cell& cell) const;
  // Marks unknown cells whose centre lies in [min, max] as soil (observed).
  void MarkObserved(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m);
  // Registers a plant: counts it in its root cell, paints its footprint
  // (cells whose centre is within radius_m) with its class (weed over crop
  // over soil over unknown) and, when treated, as treated. Throws DataError
  // for a duplicate id or a non-finite position.
  void AddPlant(const MapPlant& plant);
  const MapPlant* FindPlant(int64_t id) const;
  void AddRow(MapRow row) { rows_.push_back(std::move(row)); }
  void SetMetadata(const std::string& key, const std::string& value) { metadata_[key] = value; }

  // Whole-layer replacement for readers and merges; sizes must match the grid.
  void SetLayers(MapLayers layers);
  // Replaces the plant registry without touching the layers (readers).
  void SetPlants(std::vector<MapPlant> plants);

  size_t treated_cells() const;

 private:
  template <typename F>
  void ForFootprint(const Eigen::Vector2d& centre_m, double radius_m, F&& f);

  MapGrid grid_;
  MapLayers layers_;
  std::vector<MapPlant> plants_;
  std::unordered_map<int64_t, size_t> plant_index_;
  std::vector<MapRow> rows_;
  std::map<std::string, std::string> metadata_;
};

// Higher wins when classes meet in one cell: weed > crop > soil > unknown.
int Priority(CellClass c);
CellClass ClassOf(PlantKind k);

}  // namespace plantscale::maps
