// A run longer than one 2^15-row grid at the vehicle's 1.333 cm cells (437 m)
// exports whole: every file format and the season archive (GeoPackage), from
// the run's LCM log, as `plantscale export` does.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>
#include <unistd.h>

#include <array>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "app/archive_run.h"
#include "app/log_map.h"
#include "maps/archive.h"
#include "maps/export.h"
#include "review/synthetic_run.h"

namespace plantscale::app {
namespace {
namespace fs = std::filesystem;

struct Closer {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
using Dataset = std::unique_ptr<GDALDataset, Closer>;

constexpr double kLength = 460.0;   // m driven: 34 500 rows of 1.333 cm
constexpr double kTileEdge = 3.41;  // a 256-cell tile
// The map covers the run plus what the camera saw beyond its ends (plants
// ahead of the last frame, tiles sent 0.9 m ahead): at most 3 m.
constexpr double kViewBeyond = 3.0;

// The lines of band 1 holding any observed cell: the covered length, metres.
double CoveredLength(GDALDataset& ds, double res) {
  GDALRasterBand* band = ds.GetRasterBand(1);
  const int cols = ds.GetRasterXSize();
  std::vector<uint16_t> line(static_cast<size_t>(cols));
  int first = -1, last = -1;
  for (int l = 0; l < ds.GetRasterYSize(); ++l) {
    EXPECT_EQ(band->RasterIO(GF_Read, 0, l, cols, 1, line.data(), cols, 1, GDT_UInt16, 0, 0, nullptr), CE_None);
    const bool seen = std::any_of(line.begin(), line.end(), [](uint16_t v) { return v != 65535; });
    if (seen && first < 0) first = l;
    if (seen) last = l;
  }
  return first < 0 ? 0.0 : (last - first + 1) * res;
}

// Class (band 1) of the GeoTIFF cell holding a field point.
int ClassAt(GDALDataset& ds, const maps::Georeference& georef, const Eigen::Vector2d& field_m) {
  std::array<double, 6> gt{}, inv{};
  ds.GetGeoTransform(gt.data());
  EXPECT_TRUE(GDALInvGeoTransform(gt.data(), inv.data()));
  const Eigen::Vector2d en = georef.FieldToProjected(field_m);
  const int px = static_cast<int>(std::floor(inv[0] + inv[1] * en.x() + inv[2] * en.y()));
  const int ln = static_cast<int>(std::floor(inv[3] + inv[4] * en.x() + inv[5] * en.y()));
  uint16_t v = 0;
  EXPECT_EQ(ds.GetRasterBand(1)->RasterIO(GF_Read, px, ln, 1, 1, &v, 1, 1, GDT_UInt16, 0, 0, nullptr), CE_None);
  return v;
}

const maps::MapPlant& LastCrop(const maps::CropMap& map) {
  const maps::MapPlant* last = nullptr;
  for (const maps::MapPlant& p : map.plants()) {
    if (p.kind == maps::PlantKind::kCrop && (last == nullptr || p.position_m.y() > last->position_m.y())) last = &p;
  }
  EXPECT_NE(last, nullptr);
  return *last;
}

TEST(LongRunExport, A460MetreLogExportsWholeToEveryFormatAndTheArchive) {
  const fs::path dir = fs::temp_directory_path() / ("plantscale_longrun_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  review::SyntheticRunOptions o;
  o.length_m = kLength;
  o.speed_m_s = 2.0;
  o.cell_m = 0.01333;  // the vehicle's treatment-map cell
  o.tile_cells = 256;  // and its tile
  o.seed = 11;
  review::WriteSyntheticLog(dir / "run.lcmlog", o);

  LogMapReport report;
  const maps::CropMap map = CropMapFromLog(dir / "run.lcmlog", report);
  ASSERT_GT(map.grid().rows(), 32768);  // beyond the old limit
  const maps::MapPlant& last = LastCrop(map);
  EXPECT_GT(last.position_m.y(), kLength - 1.0);  // crops every 0.45 m up to the end

  maps::ExportOptions options;
  options.formats = maps::AllExportFormats();
  options.anchor = maps::GeoAnchorOptions{52.0, -0.4, 0.0, 0};
  maps::ExportMap(map, dir / "out", options);
  const maps::Georeference georef(*options.anchor);

  GDALAllRegister();
  for (const char* tif : {"map.tif", "map_northup.tif"}) {
    Dataset ds(GDALDataset::Open((dir / "out" / tif).c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    ASSERT_TRUE(ds) << tif;
    // Covered: the whole run, and no more than the camera saw beyond it.
    const double covered = CoveredLength(*ds, map.grid().resolution_m());
    EXPECT_GE(covered, kLength - 0.5) << tif;
    EXPECT_LE(covered, kLength + kViewBeyond) << tif;
    EXPECT_EQ(ClassAt(*ds, georef, last.position_m), 1) << tif << ": the last crop plant";
  }
  Dataset gpkg(GDALDataset::Open((dir / "out" / "map.gpkg").c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY));
  ASSERT_TRUE(gpkg);
  OGRLayer* plants = gpkg->GetLayerByName("plants");
  ASSERT_NE(plants, nullptr);
  EXPECT_EQ(plants->GetFeatureCount(), static_cast<GIntBig>(map.plants().size()));
  plants->SetAttributeFilter(("plant_id = " + std::to_string(last.id)).c_str());
  std::unique_ptr<OGRFeature> f(plants->GetNextFeature());
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->GetFieldAsDouble("field_y_m"), last.position_m.y(), 1e-6);

  // The PNG: panels side by side (a 460 m strip one picture high would be a line).
  const cv::Mat png = cv::imread((dir / "out" / "map.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  EXPECT_GT(png.cols, 600);
  EXPECT_LT(png.rows, 1600);
  // ISOXML: north-aligned grid at heading 0 is the map's grid: 4 bytes a cell.
  EXPECT_EQ(fs::file_size(dir / "out" / "TASKDATA" / "GRD00001.BIN") % 4, 0u);
  EXPECT_GE(fs::file_size(dir / "out" / "TASKDATA" / "GRD00001.BIN"), 4u * map.grid().size() * 99 / 100);

  // The archive: the run's map tiles span the whole run.
  maps::ArchiveRun run = ArchiveRunFromLog(dir / "run.lcmlog");
  run.field = "long";
  maps::AppendRun((dir / "season.gpkg").string(), run, map, options.anchor);
  Dataset season(GDALDataset::Open((dir / "season.gpkg").c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY));
  ASSERT_TRUE(season);
  std::unique_ptr<OGRLayer, void (*)(OGRLayer*)> tiles(
      season->ExecuteSQL("SELECT MIN(y0_m), MAX(y0_m + rows * resolution_m) FROM map_tiles", nullptr, nullptr),
      [](OGRLayer*) {});
  ASSERT_NE(tiles, nullptr);
  std::unique_ptr<OGRFeature> span(tiles->GetNextFeature());
  ASSERT_TRUE(span);
  // Whole tiles: up to one tile edge more than the raster.
  EXPECT_GE(span->GetFieldAsDouble(1) - span->GetFieldAsDouble(0), kLength - 0.5);
  EXPECT_LE(span->GetFieldAsDouble(1) - span->GetFieldAsDouble(0), kLength + kViewBeyond + kTileEdge);
  span.reset();
  season->ReleaseResultSet(tiles.release());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace plantscale::app
