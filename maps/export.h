#pragma once
// Export of a CropMap into a folder of GIS files (GDAL), a PNG and an
// ISO 11783-10 task. Every file is written into a staging folder inside
// `dir` and moved into place only when all requested formats succeeded.
//
//   format   file(s) in dir                        CRS
//   gtiff    map.tif                               export CRS (UTM or --epsg), grid along the rows
//   northup  map_northup.tif                       the same, resampled north-up (nearest)
//   gpkg     map.gpkg                              export CRS
//   geojson  plants.geojson                        WGS84 lon/lat (RFC 7946)
//   csv      plants.csv                            X, Y in the export CRS
//   png      map.png                               field frame, +y up
//   isoxml   TASKDATA/TASKDATA.XML, GRD00001.BIN   WGS84, north-aligned grid
//   map      map.psmap                             native (map_file.h)

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "maps/crop_map.h"
#include "maps/georef.h"

namespace plantscale::maps {

struct IsoxmlOptions {
  // Setpoint of treated cells, DDI 1 (Setpoint Volume Per Area Application
  // Rate, mm³/m²; 1 L/ha = 100 mm³/m²). Untreated cells get 0.
  double rate_l_per_ha = 200.0;
  double cell_size_m = 0.0;  // 0: the map's resolution
  OptionErrors Validate() const;
};

// Shortest text that reads back as exactly `value` (metadata numbers).
std::string ExactText(double value);

// Names accepted by ExportOptions::formats, in export order.
const std::vector<std::string>& AllExportFormats();
// Formats that need a georeference (all but png and map).
bool NeedsGeoreference(const std::string& format);

struct ExportOptions {
  std::vector<std::string> formats = AllExportFormats();
  std::optional<GeoAnchorOptions> anchor;  // required by the georeferenced formats
  IsoxmlOptions isoxml;
  OptionErrors Validate() const;  // keys: formats, anchor.*, isoxml.*
};

struct ExportResult {
  std::vector<std::filesystem::path> files;  // final paths, in dir
  int epsg = 0;                              // 0 when not georeferenced
  double geotransform_error_m = 0.0;         // affine raster georeference vs exact
};

// (formats done, formats in all, format being written)
using ExportProgress = std::function<void(int done, int total, const std::string& format)>;

// Throws InvalidOptionsError (bad options, unknown EPSG, origin out of
// range), MapIoError (unwritable folder, disk full; names the file).
ExportResult ExportMap(const CropMap& map, const std::filesystem::path& dir,
                       const ExportOptions& options, const ExportProgress& progress = {});

}  // namespace plantscale::maps
