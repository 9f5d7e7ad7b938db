// GeoTIFF export and the treated-area polygons (both from raster bands).
#include <gdal_alg.h>

#include <algorithm>

#include "maps/export.h"
#include "maps/gdal_dataset.h"
#include "maps/gdal_util.h"
#include "maps/map_errors.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace {

constexpr uint16_t kNoData = 65535;
const char* const kBandNames[] = {"class", "crop_count", "weed_count", "treated"};

// Band `b` in raster order: line 0 is the map's last row (largest y).
std::vector<uint16_t> BandValues(const CropMap& map, int b) {
  const MapGrid& g = map.grid();
  const MapLayers& l = map.layers();
  std::vector<uint16_t> out(g.size());
  for (int line = 0; line < g.rows(); ++line) {
    for (int col = 0; col < g.cols(); ++col) {
      const size_t i = g.Index({col, g.rows() - 1 - line});
      const size_t o =
          static_cast<size_t>(line) * static_cast<size_t>(g.cols()) + static_cast<size_t>(col);
      const bool unknown = l.cls[i] == static_cast<uint8_t>(CellClass::kUnknown);
      const uint16_t v = b == 0   ? l.cls[i]
                         : b == 1 ? l.crop_count[i]
                         : b == 2 ? l.weed_count[i]
                                  : l.treated[i];
      out[o] = unknown ? kNoData : v;
    }
  }
  return out;
}

void SetGeoreference(GDALDataset& ds, const CropMap& map, const Georeference& georef,
                     const std::filesystem::path& file) {
  std::array<double, 6> gt = georef.GeoTransform(map.grid());
  const OGRSpatialReference srs = ProjectedSrs(georef);
  if (ds.SetGeoTransform(gt.data()) != CE_None || ds.SetSpatialRef(&srs) != CE_None) {
    ThrowGdal(file, "cannot set the georeference");
  }
}

void WriteBand(GDALDataset& ds, const CropMap& map, int b, const std::filesystem::path& file) {
  GDALRasterBand* band = ds.GetRasterBand(b + 1);
  std::vector<uint16_t> values = BandValues(map, b);
  band->SetDescription(kBandNames[b]);
  band->SetNoDataValue(kNoData);
  if (band->RasterIO(GF_Write, 0, 0, map.grid().cols(), map.grid().rows(), values.data(),
                     map.grid().cols(), map.grid().rows(), GDT_UInt16, 0, 0, nullptr) != CE_None) {
    ThrowGdal(file, std::string("cannot write band ") + kBandNames[b]);
  }
}

void BuildOverviews(GDALDataset& ds, const MapGrid& g, const std::filesystem::path& file) {
  std::vector<int> levels;
  for (int f = 2; std::max(g.cols(), g.rows()) / f >= 16; f *= 2) levels.push_back(f);
  if (levels.empty()) return;
  if (ds.BuildOverviews("NEAREST", static_cast<int>(levels.size()), levels.data(), 0, nullptr,
                        nullptr, nullptr) != CE_None) {
    ThrowGdal(file, "cannot build overviews");
  }
}

}  // namespace

void WriteGeoTiff(const CropMap& map, const Georeference& georef,
                  const std::filesystem::path& file) {
  GdalErrorScope scope;
  const MapGrid& g = map.grid();
  MemoryFile mem(file);
  DatasetPtr ds = CreateDataset("GTiff", mem, g.cols(), g.rows(), 4, GDT_UInt16,
                                {"COMPRESS=DEFLATE", "TILED=YES", "INTERLEAVE=BAND"});
  SetGeoreference(*ds, map, georef, file);
  for (int b = 0; b < 4; ++b) WriteBand(*ds, map, b, file);
  ds->SetMetadataItem("CLASS_CODES", "0=soil,1=crop,2=weed,65535=unknown (nodata)");
  ds->SetMetadataItem("RASTER_ORDER", "line 0 = largest field y; column 0 = smallest field x");
  ds->SetMetadataItem("RESOLUTION_M", ExactText(g.resolution_m()).c_str());
  for (const auto& [k, v] : map.metadata()) ds->SetMetadataItem(k.c_str(), v.c_str(), "PLANTSCALE");
  BuildOverviews(*ds, g, file);
  CloseAndCopy(ds, mem);
}

void WriteTreatedPolygons(const CropMap& map, const Georeference& georef, OGRLayer& layer,
                          const std::filesystem::path& path) {
  const MapGrid& g = map.grid();
  DatasetPtr mem = CreateMemRaster(g.cols(), g.rows(), 1, GDT_UInt16);
  SetGeoreference(*mem, map, georef, path);
  GDALRasterBand* band = mem->GetRasterBand(1);
  std::vector<uint16_t> treated = BandValues(map, 3);
  for (uint16_t& v : treated) v = v == 1 ? 1 : 0;
  if (band->RasterIO(GF_Write, 0, 0, g.cols(), g.rows(), treated.data(), g.cols(), g.rows(),
                     GDT_UInt16, 0, 0, nullptr) != CE_None ||
      GDALPolygonize(GDALRasterBand::ToHandle(band), GDALRasterBand::ToHandle(band),
                     OGRLayer::ToHandle(&layer), 0, nullptr, nullptr, nullptr) != CE_None) {
    ThrowGdal(path, "cannot polygonize the treated area");
  }
}

}  // namespace plantscale::maps
