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

// Closes the dataset; a scratch raster's memory file goes with it.
struct DatasetCloser {
  void operator()(GDALDataset* d) const;
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

// GDAL drivers do not all report failed writes (GeoJSON ignores a full
// disk), so every dataset is written into GDAL's memory file system
// (/vsimem/) and then copied to disk with checked writes.
class MemoryFile {
 public:
  explicit MemoryFile(const std::filesystem::path& disk_path);
  ~MemoryFile();  // unlinks the memory file
  MemoryFile(const MemoryFile&) = delete;
  MemoryFile& operator=(const MemoryFile&) = delete;

  const std::string& vsi_path() const { return vsi_path_; }
  // Writes the memory file to disk_path; throws MapIoError (disk full, ...).
  void CopyToDisk() const;

 private:
  std::filesystem::path disk_path_;
  std::string vsi_path_;
};

// Creates a dataset with `driver` (raster when bands > 0, else vector).
// Throws MapIoError naming the path with GDAL's reason.
DatasetPtr CreateDataset(const char* driver, const MemoryFile& file, int cols = 0, int rows = 0,
                         int bands = 0, GDALDataType type = GDT_Unknown,
                         const std::vector<std::string>& options = {});
// Closes the dataset, checks GDAL reported no failure, then copies the
// memory file to disk. Throws MapIoError naming the disk path.
void CloseAndCopy(DatasetPtr& dataset, const MemoryFile& file);
// An intermediate raster (polygonizing, warping): a tiled, compressed
// GeoTIFF in GDAL's memory file system, removed when the dataset closes.
// Compressed because a km-long map at the vehicle's cells is millions of
// mostly uniform cells: written strip by strip it costs its compressed
// size (plus GDAL's block cache), not 2 bytes a cell as a MEM raster would.
DatasetPtr CreateScratchRaster(int cols, int rows, int bands, GDALDataType type);

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
