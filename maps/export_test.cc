// Write every format, then read it back with GDAL (and OpenCV, and GDAL's
// XML parser for ISOXML) and compare with the map and with an independent
// expectation of where plants land.
#include "maps/export.h"

#include <cpl_minixml.h>
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "maps/map_file.h"
#include "maps/test_maps.h"

namespace plantscale::maps {
namespace {

namespace fs = std::filesystem;
using testing::ExpectedProjected;
using testing::GeodesicDistanceM;
using testing::GeodesicLonLat;
using testing::SyntheticMap;
using testing::TempDir;
using testing::TestAnchor;

struct Closer {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
using Dataset = std::unique_ptr<GDALDataset, Closer>;

Dataset Open(const fs::path& file, unsigned flags) {
  Dataset ds(GDALDataset::Open(file.string().c_str(), flags | GDAL_OF_READONLY));
  EXPECT_TRUE(ds) << file;
  return ds;
}

class ExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    GDALAllRegister();
    ExportOptions options;
    options.anchor = anchor_;
    result_ = ExportMap(map_, dir_.path(), options);
  }
  const CropMap map_ = SyntheticMap();
  const GeoAnchorOptions anchor_ = TestAnchor(30.0);
  TempDir dir_;
  ExportResult result_;
};

TEST_F(ExportTest, WritesEveryFileAndNoTemporaries) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir_.path())) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"TASKDATA", "map.gpkg", "map.png", "map.psmap",
                                             "map.tif", "map_northup.tif", "plants.csv", "plants.geojson"}));
  EXPECT_EQ(result_.epsg, 32630);
}

TEST_F(ExportTest, ExportingAgainReplacesFilesAndTheTaskFolder) {
  const auto before = fs::last_write_time(dir_.path() / "TASKDATA" / "TASKDATA.XML");
  ExportOptions options;
  options.anchor = TestAnchor(45.0);
  const ExportResult again = ExportMap(map_, dir_.path(), options);
  EXPECT_EQ(again.files.size(), 8u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_.path()), {}), 8);  // no staging, no .old
  EXPECT_GE(fs::last_write_time(dir_.path() / "TASKDATA" / "TASKDATA.XML"), before);
  EXPECT_EQ(std::stod(LoadMap(dir_.path() / "map.psmap").metadata().at("heading_deg")), 45.0);
}

TEST_F(ExportTest, GeoTiffHasIdenticalCellsCrsGeotransformOverviewsAndNodata) {
  Dataset ds = Open(dir_.path() / "map.tif", GDAL_OF_RASTER);
  ASSERT_TRUE(ds);
  const MapGrid& g = map_.grid();
  ASSERT_EQ(ds->GetRasterCount(), 4);
  ASSERT_EQ(ds->GetRasterXSize(), g.cols());
  ASSERT_EQ(ds->GetRasterYSize(), g.rows());
  EXPECT_STREQ(ds->GetSpatialRef()->GetAuthorityCode(nullptr), "32630");
  std::array<double, 6> gt{};
  ds->GetGeoTransform(gt.data());
  const std::array<double, 6> expected = Georeference(anchor_).GeoTransform(g);
  for (int i = 0; i < 6; ++i)
    EXPECT_NEAR(gt[static_cast<size_t>(i)], expected[static_cast<size_t>(i)], 1e-9);
  const std::vector<const std::vector<uint16_t>*> counts{&map_.layers().crop_count,
                                                         &map_.layers().weed_count};
  for (int b = 1; b <= 4; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    int has_nodata = 0;
    EXPECT_EQ(band->GetNoDataValue(&has_nodata), 65535.0);
    EXPECT_TRUE(has_nodata);
    EXPECT_GE(band->GetOverviewCount(), 3);  // 2×, 4×, 8× at least for 300 rows
    std::vector<uint16_t> v(g.size());
    ASSERT_EQ(band->RasterIO(GF_Read, 0, 0, g.cols(), g.rows(), v.data(), g.cols(), g.rows(),
                             GDT_UInt16, 0, 0, nullptr),
              CE_None);
    for (size_t i = 0; i < g.size(); ++i) {
      const Cell c = g.CellOf(i);
      const uint16_t got =
          v[static_cast<size_t>(g.rows() - 1 - c.row) * static_cast<size_t>(g.cols()) +
            static_cast<size_t>(c.col)];
      const uint16_t want = b == 1   ? map_.layers().cls[i]
                            : b == 4 ? map_.layers().treated[i]
                                     : (*counts[static_cast<size_t>(b - 2)])[i];
      ASSERT_EQ(got, want) << "band " << b << " cell " << c.col << "," << c.row;
    }
  }
  EXPECT_STREQ(ds->GetRasterBand(1)->GetDescription(), "class");
}

TEST_F(ExportTest, AKnownPlantFallsInItsRasterCell) {
  // The treated weed at (0.21, 2.11): its independently projected position,
  // through the inverse geotransform, lands in a pixel with weed_count 1.
  Dataset ds = Open(dir_.path() / "map.tif", GDAL_OF_RASTER);
  std::array<double, 6> gt{}, inv{};
  ds->GetGeoTransform(gt.data());
  ASSERT_TRUE(GDALInvGeoTransform(gt.data(), inv.data()));
  const Eigen::Vector2d en = ExpectedProjected(anchor_, {0.21, 2.11}, 32630);
  double px = 0, ln = 0;
  GDALApplyGeoTransform(inv.data(), en.x(), en.y(), &px, &ln);
  // The weed sits on a cell centre: pixel coordinates end in .5 (± 1e-4 px = 2 µm).
  EXPECT_NEAR(px - std::floor(px), 0.5, 1e-4);
  EXPECT_NEAR(ln - std::floor(ln), 0.5, 1e-4);
  uint16_t weeds = 0, treated = 0;
  ASSERT_EQ(ds->GetRasterBand(3)->RasterIO(GF_Read, static_cast<int>(px), static_cast<int>(ln), 1,
                                           1, &weeds, 1, 1, GDT_UInt16, 0, 0, nullptr),
            CE_None);
  ASSERT_EQ(ds->GetRasterBand(4)->RasterIO(GF_Read, static_cast<int>(px), static_cast<int>(ln), 1,
                                           1, &treated, 1, 1, GDT_UInt16, 0, 0, nullptr),
            CE_None);
  EXPECT_EQ(weeds, 1);
  EXPECT_EQ(treated, 1);
}

TEST_F(ExportTest, NorthUpGeoTiffHoldsTheSameMapOnANorthUpGrid) {
  // The map's field frame is turned 30° from north; the north-up copy is
  // resampled (nearest) on cells of the same size aligned with E and N.
  Dataset ds = Open(dir_.path() / "map_northup.tif", GDAL_OF_RASTER);
  ASSERT_TRUE(ds);
  std::array<double, 6> gt{}, inv{};
  ds->GetGeoTransform(gt.data());
  const double res = map_.grid().resolution_m();
  EXPECT_EQ(gt[2], 0.0);
  EXPECT_EQ(gt[4], 0.0);
  EXPECT_NEAR(gt[1], res, 1e-12);
  EXPECT_NEAR(gt[5], -res, 1e-12);
  EXPECT_STREQ(ds->GetSpatialRef()->GetAuthorityCode(nullptr), "32630");
  EXPECT_STREQ(ds->GetRasterBand(3)->GetDescription(), "weed_count");
  // It covers the bounding box of map.tif's four corners, cell-aligned (≤ 1 cell more each way).
  std::array<double, 6> rotated{};
  Open(dir_.path() / "map.tif", GDAL_OF_RASTER)->GetGeoTransform(rotated.data());
  const double w = map_.grid().cols(), h = map_.grid().rows();
  double e_min = 1e300, e_max = -1e300, n_min = 1e300, n_max = -1e300;
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {w, 0.0}, {0.0, h}, {w, h}}) {
    const double e = rotated[0] + x * rotated[1] + y * rotated[2], n = rotated[3] + x * rotated[4] + y * rotated[5];
    e_min = std::min(e_min, e), e_max = std::max(e_max, e), n_min = std::min(n_min, n), n_max = std::max(n_max, n);
  }
  EXPECT_LE(gt[0], e_min);
  EXPECT_GT(gt[0], e_min - res);
  EXPECT_GE(gt[3], n_max);
  EXPECT_LT(gt[3], n_max + res);
  EXPECT_NEAR(ds->GetRasterXSize(), (e_max - e_min) / res, 2.0);
  EXPECT_NEAR(ds->GetRasterYSize(), (n_max - n_min) / res, 2.0);
  EXPECT_GT(std::abs(rotated[2]), 0.1 * res);  // the source really is rotated
  // Class areas survive resampling within 3 % (nearest neighbour at 30°).
  const int cols = ds->GetRasterXSize(), rows = ds->GetRasterYSize();
  std::vector<uint16_t> cls(static_cast<size_t>(cols) * static_cast<size_t>(rows));
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, cols, rows, cls.data(), cols, rows, GDT_UInt16, 0, 0,
                                           nullptr),
            CE_None);
  for (uint16_t k : {uint16_t{0}, uint16_t{1}, uint16_t{2}}) {
    const auto want = std::count(map_.layers().cls.begin(), map_.layers().cls.end(), static_cast<uint8_t>(k));
    const auto got = std::count(cls.begin(), cls.end(), k);
    ASSERT_GT(want, 0);
    EXPECT_NEAR(static_cast<double>(got), static_cast<double>(want), 0.03 * static_cast<double>(want) + 2.0)
        << "class " << k;
  }
  EXPECT_GT(std::count(cls.begin(), cls.end(), uint16_t{65535}), 0);  // corners outside the map are nodata
  // The treated weed at (0.21, 2.11), projected independently, is within one
  // cell of a north-up pixel that counts it.
  ASSERT_TRUE(GDALInvGeoTransform(gt.data(), inv.data()));
  const Eigen::Vector2d en = ExpectedProjected(anchor_, {0.21, 2.11}, 32630);
  double px = 0, ln = 0;
  GDALApplyGeoTransform(inv.data(), en.x(), en.y(), &px, &ln);
  uint16_t weeds[9] = {};
  ASSERT_EQ(ds->GetRasterBand(3)->RasterIO(GF_Read, static_cast<int>(px) - 1, static_cast<int>(ln) - 1, 3, 3, weeds,
                                           3, 3, GDT_UInt16, 0, 0, nullptr),
            CE_None);
  EXPECT_NE(std::count(std::begin(weeds), std::end(weeds), uint16_t{1}), 0);
}

// Every plant of `layer` matches the map's attributes and lies within 1 mm
// of the independent expectation; `lon_lat` for WGS84 layers.
void ExpectPlants(OGRLayer& layer, const CropMap& map, const GeoAnchorOptions& a, bool lon_lat) {
  ASSERT_EQ(layer.GetFeatureCount(), static_cast<GIntBig>(map.plants().size()));
  double worst_m = 0.0;
  for (const auto& f : layer) {
    const MapPlant* p = map.FindPlant(f->GetFieldAsInteger64("plant_id"));
    ASSERT_NE(p, nullptr);
    EXPECT_STREQ(f->GetFieldAsString("class"), ToString(p->kind));
    EXPECT_EQ(f->GetFieldAsInteger("treated") != 0, p->treated);
    EXPECT_EQ(f->GetFieldAsString("why"), p->why);
    EXPECT_NEAR(f->GetFieldAsDouble("confidence"), p->confidence, 1e-9);
    EXPECT_NEAR(f->GetFieldAsDouble("radius_m"), p->radius_m, 1e-9);
    const OGRPoint* pt = f->GetGeometryRef()->toPoint();
    const Eigen::Vector2d got(pt->getX(), pt->getY());
    worst_m =
        std::max(worst_m, lon_lat ? GeodesicDistanceM(got, GeodesicLonLat(a, p->position_m))
                                  : (got - ExpectedProjected(a, p->position_m, 32630)).norm());
  }
  EXPECT_LT(worst_m, 1e-3);  // 1 mm
  ::testing::Test::RecordProperty(lon_lat ? "worst_lonlat_error_um" : "worst_projected_error_um",
                                  std::to_string(worst_m * 1e6));
}

TEST_F(ExportTest, GeoPackagePlantsRowsTreatedAreasAndMetadata) {
  Dataset ds = Open(dir_.path() / "map.gpkg", GDAL_OF_VECTOR);
  ASSERT_TRUE(ds);
  OGRLayer* plants = ds->GetLayerByName("plants");
  ASSERT_NE(plants, nullptr);
  EXPECT_STREQ(plants->GetSpatialRef()->GetAuthorityCode(nullptr), "32630");
  ExpectPlants(*plants, map_, anchor_, false);
  OGRLayer* rows = ds->GetLayerByName("rows");
  ASSERT_NE(rows, nullptr);
  ASSERT_EQ(rows->GetFeatureCount(), 3);
  for (const auto& f : *rows) EXPECT_NEAR(f->GetFieldAsDouble("length_m"), 4.5, 1e-9);
  OGRLayer* treated = ds->GetLayerByName("treated_areas");
  ASSERT_NE(treated, nullptr);
  double area = 0.0;
  for (const auto& f : *treated) area += f->GetGeometryRef()->toPolygon()->get_Area();
  // 9 cells of 4 cm²; UTM areas are scaled by k² ≈ 0.99926 here (tolerance 0.2 %).
  EXPECT_NEAR(area, 9 * 0.0004, 0.002 * 9 * 0.0004);
  OGRLayer* meta = ds->GetLayerByName("run_metadata");
  ASSERT_NE(meta, nullptr);
  std::map<std::string, std::string> kv;
  for (const auto& f : *meta) kv[f->GetFieldAsString("key")] = f->GetFieldAsString("value");
  EXPECT_EQ(kv["source"], "synthetic test map");
  EXPECT_EQ(kv["export_epsg"], "32630");
  EXPECT_EQ(std::stod(kv["heading_deg"]), 30.0);
}

TEST_F(ExportTest, GeoJsonIsWgs84LonLatWithinAMillimetre) {
  Dataset ds = Open(dir_.path() / "plants.geojson", GDAL_OF_VECTOR);
  ASSERT_TRUE(ds);
  OGRLayer* layer = ds->GetLayer(0);
  EXPECT_STREQ(layer->GetSpatialRef()->GetAuthorityCode(nullptr), "4326");
  ExpectPlants(*layer, map_, anchor_, true);
}

TEST_F(ExportTest, CsvHasProjectedXYAndAttributes) {
  Dataset ds = Open(dir_.path() / "plants.csv", GDAL_OF_VECTOR);
  ASSERT_TRUE(ds);
  OGRLayer* layer = ds->GetLayer(0);
  ASSERT_EQ(layer->GetFeatureCount(), static_cast<GIntBig>(map_.plants().size()));
  double worst = 0.0;
  for (const auto& f : *layer) {
    const MapPlant* p = map_.FindPlant(f->GetFieldAsInteger64("plant_id"));
    ASSERT_NE(p, nullptr);
    const Eigen::Vector2d xy(f->GetFieldAsDouble("X"), f->GetFieldAsDouble("Y"));
    worst = std::max(worst, (xy - ExpectedProjected(anchor_, p->position_m, 32630)).norm());
    EXPECT_STREQ(f->GetFieldAsString("class"), ToString(p->kind));
  }
  EXPECT_LT(worst, 1e-3);  // 1 mm (CSV keeps ~15 significant digits)
  RecordProperty("worst_csv_error_um", std::to_string(worst * 1e6));
}

TEST_F(ExportTest, PngShowsClassesAndLegend) {
  const cv::Mat img = cv::imread((dir_.path() / "map.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_GT(img.cols, map_.grid().cols() + 250);  // map plus legend panel
  int crop = 0, weed = 0;
  for (auto it = img.begin<cv::Vec3b>(); it != img.end<cv::Vec3b>(); ++it) {
    crop += *it == cv::Vec3b(60, 170, 40);
    weed += *it == cv::Vec3b(40, 40, 220);
  }
  EXPECT_GT(crop, 1000);  // 30 crops of ≈ 50 cells, each ≥ 1 px, plus the legend swatch
  EXPECT_GE(weed, 22 * 18 - 2 * 22 - 2 * 18);  // at least the legend swatch (inside its border)
}

TEST_F(ExportTest, IsoxmlGridIsReadableAndMarksTheTreatedWeed) {
  const fs::path folder = dir_.path() / "TASKDATA";
  CPLXMLNode* root = CPLParseXMLFile((folder / "TASKDATA.XML").string().c_str());
  ASSERT_NE(root, nullptr);
  const CPLXMLNode* grd = CPLGetXMLNode(root, "=ISO11783_TaskData.TSK.GRD");
  ASSERT_NE(grd, nullptr);
  const double min_lat = CPLAtof(CPLGetXMLValue(grd, "A", "")),
               min_lon = CPLAtof(CPLGetXMLValue(grd, "B", ""));
  const double dlat = CPLAtof(CPLGetXMLValue(grd, "C", "")),
               dlon = CPLAtof(CPLGetXMLValue(grd, "D", ""));
  const int cols = atoi(CPLGetXMLValue(grd, "E", "0")), rows = atoi(CPLGetXMLValue(grd, "F", "0"));
  EXPECT_STREQ(CPLGetXMLValue(grd, "I", ""), "2");
  EXPECT_STREQ(CPLGetXMLValue(grd, "G", ""), "GRD00001");
  EXPECT_STREQ(CPLGetXMLValue(root, "=ISO11783_TaskData.TSK.TZN.PDV.A", ""), "0001");
  const size_t bytes = static_cast<size_t>(atoll(CPLGetXMLValue(grd, "H", "0")));
  CPLDestroyXMLNode(root);
  ASSERT_EQ(fs::file_size(folder / "GRD00001.BIN"), bytes);
  ASSERT_EQ(bytes, static_cast<size_t>(cols) * static_cast<size_t>(rows) * 4);
  // Cell size: 2 cm north and east, within 1 µm.
  EXPECT_NEAR(GeodesicDistanceM({min_lon, min_lat}, {min_lon, min_lat + dlat}), 0.02, 1e-6);
  EXPECT_NEAR(GeodesicDistanceM({min_lon, min_lat}, {min_lon + dlon, min_lat}), 0.02, 1e-6);
  std::vector<int32_t> cells(static_cast<size_t>(cols) * static_cast<size_t>(rows));
  std::ifstream(folder / "GRD00001.BIN", std::ios::binary)
      .read(reinterpret_cast<char*>(cells.data()), static_cast<std::streamsize>(bytes));
  auto at = [&](const Eigen::Vector2d& ll) {
    const int c = static_cast<int>((ll.x() - min_lon) / dlon),
              r = static_cast<int>((ll.y() - min_lat) / dlat);
    return cells[static_cast<size_t>(r) * static_cast<size_t>(cols) + static_cast<size_t>(c)];
  };
  EXPECT_EQ(at(GeodesicLonLat(anchor_, {0.21, 2.11})), 20000);  // 200 L/ha = 20000 mm³/m²
  EXPECT_EQ(at(GeodesicLonLat(anchor_, {0.0, 1.0})), 0);        // a crop
  const long treated = std::count(cells.begin(), cells.end(), 20000);
  EXPECT_NEAR(static_cast<double>(treated), 9.0, 4.0);  // 9 map cells, resampled on a rotated grid
}

TEST_F(ExportTest, NativeMapKeepsTheAnchorForTheNextExport) {
  const CropMap again = LoadMap(dir_.path() / "map.psmap");
  EXPECT_EQ(again.layers().cls, map_.layers().cls);
  EXPECT_EQ(std::stod(again.metadata().at("origin_lat_deg")), 52.0);
  EXPECT_EQ(std::stod(again.metadata().at("origin_lon_deg")), -0.4);
  EXPECT_EQ(std::stod(again.metadata().at("heading_deg")), 30.0);
}

TEST_F(ExportTest, RasterGeoreferenceIsWithinAMicrometreOfExact) {
  EXPECT_LT(result_.geotransform_error_m, 1e-6);
  RecordProperty("geotransform_error_um", std::to_string(result_.geotransform_error_m * 1e6));
}

}  // namespace
}  // namespace plantscale::maps
