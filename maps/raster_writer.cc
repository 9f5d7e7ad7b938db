// GeoTIFF export and the treated-area polygons (both from raster bands).
#include <gdal_alg.h>
#include <gdalwarper.h>

#include <algorithm>
#include <cmath>

#include "maps/export.h"
#include "maps/gdal_dataset.h"
#include "maps/gdal_util.h"
#include "maps/map_errors.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace {

constexpr uint16_t kNoData = 65535;
const char* const kBandNames[] = {"class", "crop_count", "weed_count", "treated"};
// BigTIFF when the file might pass 4 GB (a long run's uncompressed bands can).
const std::vector<std::string> kTiffOptions{"COMPRESS=DEFLATE", "TILED=YES", "INTERLEAVE=BAND",
                                            "BIGTIFF=IF_SAFER"};

constexpr int kStripLines = 256;  // lines per write: memory stays bounded on a km-long map

// Lines [line0, line0 + lines) of band `b` in raster order: line 0 is the
// map's last row (largest y).
std::vector<uint16_t> BandStrip(const CropMap& map, int b, int line0, int lines) {
  const MapGrid& g = map.grid();
  const MapLayers& l = map.layers();
  std::vector<uint16_t> out(static_cast<size_t>(lines) * static_cast<size_t>(g.cols()));
  for (int k = 0; k < lines; ++k) {
    const size_t row0 = g.Index({0, g.rows() - 1 - (line0 + k)});
    for (int col = 0; col < g.cols(); ++col) {
      const size_t i = row0 + static_cast<size_t>(col);
      const size_t o = static_cast<size_t>(k) * static_cast<size_t>(g.cols()) + static_cast<size_t>(col);
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
  band->SetDescription(kBandNames[b]);
  band->SetNoDataValue(kNoData);
  const int cols = map.grid().cols();
  for (int line0 = 0; line0 < map.grid().rows(); line0 += kStripLines) {
    const int lines = std::min(kStripLines, map.grid().rows() - line0);
    std::vector<uint16_t> values = BandStrip(map, b, line0, lines);
    if (band->RasterIO(GF_Write, 0, line0, cols, lines, values.data(), cols, lines, GDT_UInt16, 0, 0,
                       nullptr) != CE_None) {
      ThrowGdal(file, std::string("cannot write band ") + kBandNames[b]);
    }
  }
}

void BuildOverviews(GDALDataset& ds, const std::filesystem::path& file) {
  std::vector<int> levels;
  for (int f = 2; std::max(ds.GetRasterXSize(), ds.GetRasterYSize()) / f >= 16; f *= 2) levels.push_back(f);
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
  DatasetPtr ds = CreateDataset("GTiff", mem, g.cols(), g.rows(), 4, GDT_UInt16, kTiffOptions);
  SetGeoreference(*ds, map, georef, file);
  for (int b = 0; b < 4; ++b) WriteBand(*ds, map, b, file);
  ds->SetMetadataItem("CLASS_CODES", "0=soil,1=crop,2=weed,65535=unknown (nodata)");
  ds->SetMetadataItem("RASTER_ORDER", "line 0 = largest field y; column 0 = smallest field x");
  ds->SetMetadataItem("RESOLUTION_M", ExactText(g.resolution_m()).c_str());
  for (const auto& [k, v] : map.metadata()) ds->SetMetadataItem(k.c_str(), v.c_str(), "PLANTSCALE");
  BuildOverviews(*ds, file);
  CloseAndCopy(ds, mem);
}

void WriteNorthUpGeoTiff(const CropMap& map, const Georeference& georef,
                         const std::filesystem::path& file) {
  GdalErrorScope scope;
  const MapGrid& g = map.grid();
  DatasetPtr src = CreateScratchRaster(g.cols(), g.rows(), 4, GDT_UInt16);
  SetGeoreference(*src, map, georef, file);
  for (int b = 0; b < 4; ++b) WriteBand(*src, map, b, file);

  // The north-up grid: same cell size, cell edges on multiples of it, covering
  // the four corners of the (rotated) map.
  const std::array<double, 6> gt = georef.GeoTransform(g);
  double min_e = INFINITY, max_e = -INFINITY, min_n = INFINITY, max_n = -INFINITY;
  for (const auto& [px, ln] : {std::pair{0, 0}, {g.cols(), 0}, {0, g.rows()}, {g.cols(), g.rows()}}) {
    const double e = gt[0] + px * gt[1] + ln * gt[2];
    const double n = gt[3] + px * gt[4] + ln * gt[5];
    min_e = std::min(min_e, e), max_e = std::max(max_e, e);
    min_n = std::min(min_n, n), max_n = std::max(max_n, n);
  }
  const double res = g.resolution_m();
  const double e0 = std::floor(min_e / res) * res, n0 = std::ceil(max_n / res) * res;
  const int cols = static_cast<int>(std::ceil((max_e - e0) / res));
  const int rows = static_cast<int>(std::ceil((n0 - min_n) / res));
  MemoryFile mem(file);
  DatasetPtr dst = CreateDataset("GTiff", mem, cols, rows, 4, GDT_UInt16, kTiffOptions);
  std::array<double, 6> north_up{e0, res, 0.0, n0, 0.0, -res};
  const OGRSpatialReference srs = ProjectedSrs(georef);
  if (dst->SetGeoTransform(north_up.data()) != CE_None || dst->SetSpatialRef(&srs) != CE_None) {
    ThrowGdal(file, "cannot set the georeference");
  }
  for (int b = 0; b < 4; ++b) {
    GDALRasterBand* band = dst->GetRasterBand(b + 1);
    band->SetDescription(kBandNames[b]);
    band->SetNoDataValue(kNoData);
  }

  // Nearest neighbour: cell values are classes and counts, never blends.
  GDALWarpOptions* wo = GDALCreateWarpOptions();
  wo->hSrcDS = GDALDataset::ToHandle(src.get());
  wo->hDstDS = GDALDataset::ToHandle(dst.get());
  wo->eResampleAlg = GRA_NearestNeighbour;
  wo->nBandCount = 4;
  wo->panSrcBands = static_cast<int*>(CPLMalloc(sizeof(int) * 4));
  wo->panDstBands = static_cast<int*>(CPLMalloc(sizeof(int) * 4));
  wo->padfSrcNoDataReal = static_cast<double*>(CPLMalloc(sizeof(double) * 4));
  wo->padfDstNoDataReal = static_cast<double*>(CPLMalloc(sizeof(double) * 4));
  for (int b = 0; b < 4; ++b) {
    wo->panSrcBands[b] = wo->panDstBands[b] = b + 1;
    wo->padfSrcNoDataReal[b] = wo->padfDstNoDataReal[b] = kNoData;
  }
  wo->papszWarpOptions = CSLSetNameValue(wo->papszWarpOptions, "INIT_DEST", "NO_DATA");
  wo->pTransformerArg = GDALCreateGenImgProjTransformer(wo->hSrcDS, nullptr, wo->hDstDS, nullptr, FALSE, 0.0, 0);
  wo->pfnTransformer = GDALGenImgProjTransform;
  CPLErr warped = CE_Failure;
  if (wo->pTransformerArg != nullptr) {
    GDALWarpOperation op;
    if (op.Initialize(wo) == CE_None) warped = op.ChunkAndWarpImage(0, 0, cols, rows);
    GDALDestroyGenImgProjTransformer(wo->pTransformerArg);
  }
  GDALDestroyWarpOptions(wo);
  if (warped != CE_None) ThrowGdal(file, "cannot resample the map north-up");

  dst->SetMetadataItem("CLASS_CODES", "0=soil,1=crop,2=weed,65535=unknown (nodata)");
  dst->SetMetadataItem("RASTER_ORDER", "north-up: line 0 = northmost, column 0 = westmost");
  dst->SetMetadataItem("RESAMPLING", "nearest neighbour from the field-frame grid of map.tif");
  dst->SetMetadataItem("RESOLUTION_M", ExactText(res).c_str());
  for (const auto& [k, v] : map.metadata()) dst->SetMetadataItem(k.c_str(), v.c_str(), "PLANTSCALE");
  BuildOverviews(*dst, file);
  CloseAndCopy(dst, mem);
}

void WriteTreatedBand(const CropMap& map, GDALRasterBand& band, const std::filesystem::path& path) {
  const MapGrid& g = map.grid();
  const std::vector<uint8_t>& treated = map.layers().treated;
  std::vector<uint8_t> strip;
  for (int line0 = 0; line0 < g.rows(); line0 += kStripLines) {
    const int lines = std::min(kStripLines, g.rows() - line0);
    strip.assign(static_cast<size_t>(lines) * static_cast<size_t>(g.cols()), 0);
    for (int k = 0; k < lines; ++k) {
      const size_t row0 = g.Index({0, g.rows() - 1 - (line0 + k)});
      for (int col = 0; col < g.cols(); ++col) {
        strip[static_cast<size_t>(k) * static_cast<size_t>(g.cols()) + static_cast<size_t>(col)] =
            treated[row0 + static_cast<size_t>(col)] == 1 ? 1 : 0;
      }
    }
    if (band.RasterIO(GF_Write, 0, line0, g.cols(), lines, strip.data(), g.cols(), lines, GDT_Byte, 0, 0,
                      nullptr) != CE_None) {
      ThrowGdal(path, "cannot write the treated cells");
    }
  }
}

void WriteTreatedPolygons(const CropMap& map, const Georeference& georef, OGRLayer& layer,
                          const std::filesystem::path& path) {
  const MapGrid& g = map.grid();
  DatasetPtr raster = CreateScratchRaster(g.cols(), g.rows(), 1, GDT_Byte);
  SetGeoreference(*raster, map, georef, path);
  GDALRasterBand* band = raster->GetRasterBand(1);
  WriteTreatedBand(map, *band, path);
  if (GDALPolygonize(GDALRasterBand::ToHandle(band), GDALRasterBand::ToHandle(band),
                     OGRLayer::ToHandle(&layer), 0, nullptr, nullptr, nullptr) != CE_None) {
    ThrowGdal(path, "cannot polygonize the treated area");
  }
}

}  // namespace plantscale::maps
