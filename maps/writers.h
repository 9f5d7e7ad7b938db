#pragma once
// One writer per export format (maps/ internal; ExportMap in export.h is
// the public entry). Each writes exactly the path(s) it is given and throws
// MapIoError naming the file when anything fails.

#include <filesystem>

#include "maps/crop_map.h"
#include "maps/georef.h"

class GDALRasterBand;
class OGRLayer;

namespace plantscale::maps {

struct IsoxmlOptions;

// Bands 1..4: class, crop_count, weed_count, treated (UInt16, nodata 65535
// where the class is unknown), DEFLATE, tiled, internal overviews.
void WriteGeoTiff(const CropMap& map, const Georeference& georef,
                  const std::filesystem::path& file);
// The same bands resampled (nearest neighbour) onto a north-up grid of the
// same cell size: for tools that ignore a rotated geotransform.
void WriteNorthUpGeoTiff(const CropMap& map, const Georeference& georef,
                         const std::filesystem::path& file);
// Layers plants (points), rows (lines), treated_areas (polygons), run_metadata (table).
void WriteGeoPackage(const CropMap& map, const Georeference& georef,
                     const std::filesystem::path& file);
// Plants as RFC 7946 GeoJSON (WGS84 lon/lat).
void WriteGeoJson(const CropMap& map, const Georeference& georef,
                  const std::filesystem::path& file);
// Plants as CSV: X, Y in the export CRS, then the plant attributes.
void WritePlantsCsv(const CropMap& map, const Georeference& georef,
                    const std::filesystem::path& file);
// Class picture with treated cells, legend, scale bar and (when georef) north arrow.
void WritePng(const CropMap& map, const Georeference* georef, const std::filesystem::path& file);
// ISO 11783-10 TASKDATA folder: TASKDATA.XML and GRD00001.BIN.
void WriteIsoxml(const CropMap& map, const Georeference& georef, const IsoxmlOptions& options,
                 const std::filesystem::path& folder);

// The treated layer as a Byte band (1 treated, 0 not; line 0 = largest
// field y), written 256 lines at a time.
void WriteTreatedBand(const CropMap& map, GDALRasterBand& band, const std::filesystem::path& path);
// The treated layer as polygons in the export CRS (GDALPolygonize).
void WriteTreatedPolygons(const CropMap& map, const Georeference& georef, OGRLayer& layer,
                          const std::filesystem::path& path);

}  // namespace plantscale::maps
