#include "maps/plants_layer.h"

#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <memory>

#include "maps/gdal_util.h"
#include "maps/map_errors.h"

namespace plantscale::maps {
namespace {

struct Closer {
  void operator()(GDALDataset* d) const { GDALClose(GDALDataset::ToHandle(d)); }
};

constexpr const char* kFields[] = {"plant_id", "class", "field_x_m", "field_y_m", "radius_m", "treated", "why"};

}  // namespace

std::vector<PlantsLayerRow> ReadPlantsLayer(const std::filesystem::path& gpkg) {
  EnsureGdalRegistered();
  GdalErrorScope errors;
  const char* drivers[] = {"GPKG", nullptr};
  std::unique_ptr<GDALDataset, Closer> ds(
      GDALDataset::FromHandle(GDALOpenEx(gpkg.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, drivers, nullptr, nullptr)));
  if (!ds) throw MapIoError(gpkg.string(), "not a GeoPackage, or it cannot be opened" + errors.Suffix());
  OGRLayer* layer = ds->GetLayerByName("plants");
  if (layer == nullptr) {
    throw MapIoError(gpkg.string(), "has no `plants` layer (plantscale export writes one)");
  }
  OGRFeatureDefn* defn = layer->GetLayerDefn();
  int index[std::size(kFields)];
  for (size_t i = 0; i < std::size(kFields); ++i) {
    index[i] = defn->GetFieldIndex(kFields[i]);
    if (index[i] < 0) throw MapIoError(gpkg.string(), std::string("`plants` layer has no field ") + kFields[i]);
  }
  std::vector<PlantsLayerRow> rows;
  for (const auto& f : *layer) {
    PlantsLayerRow r;
    r.plant_id = f->GetFieldAsInteger64(index[0]);
    r.kind = f->GetFieldAsString(index[1]);
    r.field_x_m = f->GetFieldAsDouble(index[2]);
    r.field_y_m = f->GetFieldAsDouble(index[3]);
    r.radius_m = f->GetFieldAsDouble(index[4]);
    r.treated = f->GetFieldAsInteger(index[5]) != 0;
    r.why = f->GetFieldAsString(index[6]);
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace plantscale::maps
