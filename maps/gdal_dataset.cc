#include "maps/gdal_dataset.h"

#include <cpl_vsi.h>

#include <atomic>
#include <fstream>

#include "maps/gdal_util.h"
#include "maps/map_errors.h"

namespace plantscale::maps {

namespace {

DatasetPtr Create(const char* driver_name, const std::string& path, const std::string& name,
                  int cols, int rows, int bands, GDALDataType type,
                  const std::vector<std::string>& options) {
  EnsureGdalRegistered();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name);
  if (driver == nullptr)
    throw MapIoError(name, std::string("GDAL has no ") + driver_name + " driver");
  CPLStringList opts;
  for (const std::string& o : options) opts.AddString(o.c_str());
  DatasetPtr ds(driver->Create(path.c_str(), cols, rows, bands, type, opts.List()));
  if (!ds) ThrowGdal(name, std::string("cannot create ") + driver_name + " file");
  return ds;
}

}  // namespace

MemoryFile::MemoryFile(const std::filesystem::path& disk_path) : disk_path_(disk_path) {
  static std::atomic<int> counter{0};
  vsi_path_ =
      "/vsimem/plantscale_" + std::to_string(++counter) + "/" + disk_path.filename().string();
  VSIMkdir(std::filesystem::path(vsi_path_).parent_path().c_str(), 0755);  // CSV wants a folder
}

MemoryFile::~MemoryFile() {
  VSIUnlink(vsi_path_.c_str());
  VSIRmdirRecursive(std::filesystem::path(vsi_path_).parent_path().c_str());
}

void MemoryFile::CopyToDisk() const {
  vsi_l_offset size = 0;
  const GByte* data = VSIGetMemFileBuffer(vsi_path_.c_str(), &size, FALSE);
  if (data == nullptr) throw MapIoError(disk_path_.string(), "GDAL wrote nothing");
  std::ofstream out(disk_path_, std::ios::binary);
  if (!out) throw MapIoError(disk_path_.string(), "cannot be created");
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) throw MapIoError(disk_path_.string(), "write failed (disk full?)");
}

DatasetPtr CreateDataset(const char* driver_name, const MemoryFile& file, int cols, int rows,
                         int bands, GDALDataType type, const std::vector<std::string>& options) {
  return Create(driver_name, file.vsi_path(), file.vsi_path(), cols, rows, bands, type, options);
}

namespace {
constexpr const char* kScratchPrefix = "/vsimem/plantscale_scratch_";
}  // namespace

void DatasetCloser::operator()(GDALDataset* d) const {
  const std::string path = d != nullptr ? d->GetDescription() : "";
  GDALClose(GDALDataset::ToHandle(d));
  if (path.rfind(kScratchPrefix, 0) == 0) VSIUnlink(path.c_str());
}

DatasetPtr CreateScratchRaster(int cols, int rows, int bands, GDALDataType type) {
  static std::atomic<int> counter{0};
  const std::string path = kScratchPrefix + std::to_string(++counter) + ".tif";
  return Create("GTiff", path, "scratch raster", cols, rows, bands, type,
                {"COMPRESS=DEFLATE", "ZLEVEL=1", "TILED=YES", "INTERLEAVE=BAND", "BIGTIFF=YES", "SPARSE_OK=YES"});
}

void CloseAndCopy(DatasetPtr& dataset, const MemoryFile& file) {
  if (dataset) dataset->FlushCache(true);
  dataset.reset();
  if (CPLGetLastErrorType() == CE_Failure || CPLGetLastErrorType() == CE_Fatal) {
    ThrowGdal(file.vsi_path(), "GDAL failed to write");
  }
  file.CopyToDisk();
}

OGRSpatialReference ProjectedSrs(const Georeference& georef) {
  OGRSpatialReference srs;
  srs.importFromEPSG(georef.epsg());
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

OGRSpatialReference Wgs84Srs() {
  OGRSpatialReference srs;
  srs.importFromEPSG(4326);
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

void AddPlantFields(OGRLayer& layer, const std::filesystem::path& path) {
  const std::pair<const char*, OGRFieldType> fields[] = {
      {"plant_id", OFTInteger64}, {"class", OFTString},    {"confidence", OFTReal},
      {"radius_m", OFTReal},      {"treated", OFTInteger}, {"why", OFTString},
      {"field_x_m", OFTReal},     {"field_y_m", OFTReal},  {"lon_deg", OFTReal},
      {"lat_deg", OFTReal},       {"easting_m", OFTReal},  {"northing_m", OFTReal}};
  for (const auto& [name, type] : fields) {
    OGRFieldDefn defn(name, type);
    if (std::string(name) == "treated") defn.SetSubType(OFSTBoolean);
    if (layer.CreateField(&defn) != OGRERR_NONE)
      ThrowGdal(path, std::string("cannot add field ") + name);
  }
}

void WritePlantFeatures(OGRLayer& layer, const CropMap& map, const Georeference& georef,
                        bool lon_lat, const std::filesystem::path& path) {
  for (const MapPlant& p : map.plants()) {
    const Eigen::Vector2d ll = georef.FieldToWgs84(p.position_m);
    const Eigen::Vector2d en = georef.FieldToProjected(p.position_m);
    OGRFeature feature(layer.GetLayerDefn());
    feature.SetField("plant_id", static_cast<GIntBig>(p.id));
    feature.SetField("class", ToString(p.kind));
    feature.SetField("confidence", p.confidence);
    feature.SetField("radius_m", p.radius_m);
    feature.SetField("treated", p.treated ? 1 : 0);
    feature.SetField("why", p.why.c_str());
    feature.SetField("field_x_m", p.position_m.x());
    feature.SetField("field_y_m", p.position_m.y());
    feature.SetField("lon_deg", ll.x());
    feature.SetField("lat_deg", ll.y());
    feature.SetField("easting_m", en.x());
    feature.SetField("northing_m", en.y());
    const Eigen::Vector2d xy = lon_lat ? ll : en;
    feature.SetGeometry(std::make_unique<OGRPoint>(xy.x(), xy.y()).get());
    if (layer.CreateFeature(&feature) != OGRERR_NONE) {
      ThrowGdal(path, "cannot write plant " + std::to_string(p.id));
    }
  }
}

}  // namespace plantscale::maps
