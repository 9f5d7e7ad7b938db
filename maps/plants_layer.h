#pragma once
// Reads back the `plants` layer of an exported GeoPackage (export.h, format
// gpkg): one row per plant with its field-frame position, so that a finished
// run can be looked at again from its map alone (plantscale station --review).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace plantscale::maps {

struct PlantsLayerRow {
  int64_t plant_id = 0;
  std::string kind;        // "crop", "weed" or "unknown"
  double field_x_m = 0.0;  // field frame
  double field_y_m = 0.0;
  double radius_m = 0.0;   // leaf-tip radius
  bool treated = false;
  std::string why;         // the treatment decision's reason, in words
};

// Throws MapIoError naming the file when it is not a GeoPackage (or cannot
// be opened), has no `plants` layer, or that layer lacks one of the fields
// above.
std::vector<PlantsLayerRow> ReadPlantsLayer(const std::filesystem::path& gpkg);

}  // namespace plantscale::maps
