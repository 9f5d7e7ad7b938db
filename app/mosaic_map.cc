#include "app/mosaic_map.h"

#include <string>
#include <utility>

namespace plantscale::app {

// The mosaic's labels are copied into the class layer as they are.
static_assert(motion::kSoilLabel == static_cast<uint8_t>(maps::CellClass::kSoil));
static_assert(motion::kPlantLabel == static_cast<uint8_t>(maps::CellClass::kCrop));
static_assert(motion::kWeedLabel == static_cast<uint8_t>(maps::CellClass::kWeed));
static_assert(motion::kUnknownLabel == static_cast<uint8_t>(maps::CellClass::kUnknown));

maps::CropMap ToCropMap(const motion::MosaicMap& mosaic) {
  maps::MapGridOptions grid;
  grid.resolution_m = mosaic.grid.resolution_m;
  grid.origin_m = mosaic.grid.origin_m;
  grid.cols = mosaic.grid.cols;
  grid.rows = mosaic.grid.rows;
  maps::CropMap map{maps::MapGrid(grid)};
  maps::MapLayers layers = map.layers();
  layers.cls = mosaic.labels;
  map.SetLayers(std::move(layers));
  int64_t id = 1;
  for (const motion::MosaicPlant& p : mosaic.plants) {
    maps::MapPlant plant;
    plant.id = id++;
    plant.position_m = p.position_m;
    plant.kind = maps::PlantKind::kCrop;
    plant.radius_m = p.radius_m;
    plant.why = "mosaic plant blob";
    map.AddPlant(plant);
  }
  map.SetMetadata("source", "motion mosaic (Sanchiz & Pla majority vote)");
  map.SetMetadata("frames", std::to_string(mosaic.frames));
  return map;
}

}  // namespace plantscale::app
