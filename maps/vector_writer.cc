// GeoPackage, GeoJSON and CSV exports (OGR vector drivers).
#include <cmath>
#include <functional>
#include <map>

#include "maps/export.h"
#include "maps/gdal_dataset.h"
#include "maps/gdal_util.h"
#include "maps/map_errors.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace fs = std::filesystem;
namespace {

OGRLayer& MakeLayer(GDALDataset& ds, const char* name, const OGRSpatialReference* srs,
                    OGRwkbGeometryType type, const fs::path& file,
                    const std::vector<std::string>& options = {}) {
  CPLStringList opts;
  for (const std::string& o : options) opts.AddString(o.c_str());
  // GDAL 3.6 takes a non-const SRS but only reads (clones) it.
  OGRLayer* layer = ds.CreateLayer(name, const_cast<OGRSpatialReference*>(srs), type, opts.List());
  if (layer == nullptr) ThrowGdal(file, std::string("cannot create layer ") + name);
  return *layer;
}

void AddField(OGRLayer& layer, const char* name, OGRFieldType type, const fs::path& file) {
  OGRFieldDefn defn(name, type);
  if (layer.CreateField(&defn) != OGRERR_NONE) ThrowGdal(file, std::string("cannot add ") + name);
}

void Create(OGRLayer& layer, OGRFeature& feature, const fs::path& file) {
  if (layer.CreateFeature(&feature) != OGRERR_NONE) {
    ThrowGdal(file, std::string("cannot write to layer ") + layer.GetName());
  }
}

void WriteRows(GDALDataset& ds, const CropMap& map, const Georeference& georef,
               const OGRSpatialReference& srs, const fs::path& file) {
  OGRLayer& layer = MakeLayer(ds, "rows", &srs, wkbLineString, file);
  AddField(layer, "row", OFTInteger, file);
  AddField(layer, "length_m", OFTReal, file);
  for (const MapRow& r : map.rows()) {
    OGRLineString line;
    double length = 0.0;
    for (size_t i = 0; i < r.points_m.size(); ++i) {
      const Eigen::Vector2d p = georef.FieldToProjected(r.points_m[i]);
      line.addPoint(p.x(), p.y());
      if (i > 0) length += (r.points_m[i] - r.points_m[i - 1]).norm();
    }
    OGRFeature f(layer.GetLayerDefn());
    f.SetField("row", r.index);
    f.SetField("length_m", length);
    f.SetGeometry(&line);
    Create(layer, f, file);
  }
}

void WriteMetadataTable(GDALDataset& ds, const CropMap& map, const Georeference& georef,
                        const fs::path& file) {
  OGRLayer& layer = MakeLayer(ds, "run_metadata", nullptr, wkbNone, file);
  AddField(layer, "key", OFTString, file);
  AddField(layer, "value", OFTString, file);
  std::map<std::string, std::string> rows = map.metadata();
  const GeoAnchorOptions& a = georef.options();
  rows["origin_lat_deg"] = ExactText(a.latitude_deg);
  rows["origin_lon_deg"] = ExactText(a.longitude_deg);
  rows["heading_deg"] = ExactText(a.heading_deg);
  rows["export_epsg"] = std::to_string(georef.epsg());
  rows["resolution_m"] = ExactText(map.grid().resolution_m());
  rows["plants"] = std::to_string(map.plants().size());
  for (const auto& [k, v] : rows) {
    OGRFeature f(layer.GetLayerDefn());
    f.SetField("key", k.c_str());
    f.SetField("value", v.c_str());
    Create(layer, f, file);
  }
}

void InTransaction(GDALDataset& ds, const fs::path& file, const std::function<void()>& write) {
  if (ds.StartTransaction() != OGRERR_NONE) ThrowGdal(file, "cannot start a transaction");
  write();
  if (ds.CommitTransaction() != OGRERR_NONE) ThrowGdal(file, "cannot commit (disk full?)");
}

}  // namespace

void WriteGeoPackage(const CropMap& map, const Georeference& georef, const fs::path& file) {
  GdalErrorScope scope;
  MemoryFile mem(file);
  DatasetPtr ds = CreateDataset("GPKG", mem);
  const OGRSpatialReference srs = ProjectedSrs(georef);
  InTransaction(*ds, file, [&] {
    OGRLayer& plants = MakeLayer(*ds, "plants", &srs, wkbPoint, file);
    AddPlantFields(plants, file);
    WritePlantFeatures(plants, map, georef, false, file);
  });
  InTransaction(*ds, file, [&] { WriteRows(*ds, map, georef, srs, file); });
  InTransaction(*ds, file, [&] {
    OGRLayer& treated = MakeLayer(*ds, "treated_areas", &srs, wkbPolygon, file);
    AddField(treated, "treated", OFTInteger, file);
    WriteTreatedPolygons(map, georef, treated, file);
  });
  InTransaction(*ds, file, [&] { WriteMetadataTable(*ds, map, georef, file); });
  CloseAndCopy(ds, mem);
}

void WriteGeoJson(const CropMap& map, const Georeference& georef, const fs::path& file) {
  GdalErrorScope scope;
  MemoryFile mem(file);
  DatasetPtr ds = CreateDataset("GeoJSON", mem);
  const OGRSpatialReference wgs84 = Wgs84Srs();
  // RFC 7946: WGS84 lon/lat; 9 decimals ≈ 0.1 mm (the default 7 is ≈ 1 cm).
  OGRLayer& layer = MakeLayer(*ds, "plants", &wgs84, wkbPoint, file,
                              {"RFC7946=YES", "COORDINATE_PRECISION=9", "WRITE_NAME=YES"});
  AddPlantFields(layer, file);
  WritePlantFeatures(layer, map, georef, true, file);
  CloseAndCopy(ds, mem);
}

void WritePlantsCsv(const CropMap& map, const Georeference& georef, const fs::path& file) {
  GdalErrorScope scope;
  MemoryFile mem(file);
  DatasetPtr ds = CreateDataset("CSV", mem);
  const OGRSpatialReference srs = ProjectedSrs(georef);
  OGRLayer& layer = MakeLayer(*ds, "plants", &srs, wkbPoint, file,
                              {"GEOMETRY=AS_XY", "STRING_QUOTING=IF_NEEDED"});
  AddPlantFields(layer, file);
  WritePlantFeatures(layer, map, georef, false, file);
  CloseAndCopy(ds, mem);
}

}  // namespace plantscale::maps
