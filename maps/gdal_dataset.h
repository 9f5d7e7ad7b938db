#pragma once
// Owning GDAL dataset handles for the exporters (maps/ internal).

#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "maps/crop_map.h"
#include "maps/georef.h"

namespace plantscale::maps {

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(GDALDataset::ToHandle(d)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

// Creates a dataset with `driver` (raster when bands > 0, else vector).
// Throws MapIoError naming the path with GDAL's reason.
DatasetPtr CreateDataset(const char* driver, const std::filesystem::path& path, int cols = 0,
                         int rows = 0, int bands = 0, GDALDataType type = GDT_Unknown,
                         const std::vector<std::string>& options = {});
// Closes the dataset; throws MapIoError if GDAL reported a failure since
// `scope` began (e.g. a write error on a full disk).
void CloseChecked(DatasetPtr& dataset, const std::filesystem::path& path);

// The export CRS as an OSR object (traditional GIS axis order).
OGRSpatialReference ProjectedSrs(const Georeference& georef);
OGRSpatialReference Wgs84Srs();

// Plant attributes shared by GeoPackage, GeoJSON and CSV layers.
void AddPlantFields(OGRLayer& layer, const std::filesystem::path& path);
// Writes one feature per plant; `lon_lat` chooses WGS84 (lon, lat)
// geometry instead of the export CRS.
void WritePlantFeatures(OGRLayer& layer, const CropMap& map, const Georeference& georef,
                        bool lon_lat, const std::filesystem::path& path);

}  // namespace plantscale::maps
