// Reading the archive: runs of a field, one plant's history, the season as
// a GeoPackage (archive.h).
#include <algorithm>
#include <map>
#include <regex>

#include "maps/archive.h"
#include "maps/archive_db.h"
#include "maps/gdal_dataset.h"
#include "maps/gdal_util.h"
#include "maps/map_errors.h"

namespace plantscale::maps {
namespace {

void CheckDate(const std::string& date, const char* key) {
  static const std::regex iso(R"(\d{4}-\d{2}-\d{2})");
  if (!date.empty() && !std::regex_match(date, iso)) {
    throw InvalidOptionsError("archive query", {{key, "expected a date YYYY-MM-DD (got '" + date + "')"}});
  }
}

OGRLayer& Table(ArchiveDb& db, const std::string& name) {
  OGRLayer* layer = FindTable(db, name);
  if (layer == nullptr) throw MapIoError(db.name, "not a plantscale archive (no table " + name + ")");
  return *layer;
}

ArchivedRun RunOf(const OGRFeature& f) {
  ArchivedRun r;
  r.run_id = f.GetFieldAsString("run_id");
  r.field = f.GetFieldAsString("field");
  r.bed = f.GetFieldAsInteger("bed");
  r.vehicle = f.GetFieldAsString("vehicle");
  r.crop_profile = f.GetFieldAsString("crop_profile");
  r.source = f.GetFieldAsString("source");
  r.start_time = f.GetFieldAsString("start_time");
  r.end_time = f.GetFieldAsString("end_time");
  r.distance_m = f.GetFieldAsDouble("distance_m");
  ArchiveFigures& g = r.figures;
  g.crop = f.GetFieldAsInteger("crop");
  g.plants_per_m = f.GetFieldAsDouble("plants_per_m");
  g.gaps = f.GetFieldAsInteger("gaps");
  g.missing = f.GetFieldAsInteger("missing");
  g.median_radius_m = f.GetFieldAsDouble("median_radius_m");
  g.weeds = f.GetFieldAsInteger("weeds");
  g.weeds_per_m2 = f.GetFieldAsDouble("weeds_per_m2");
  g.area_treated_m2 = f.GetFieldAsDouble("area_treated_m2");
  g.treated_plants = f.GetFieldAsInteger("treated_plants");
  return r;
}

std::vector<ArchivedRun> ReadRuns(OGRLayer& layer, const std::string& filter) {
  layer.SetAttributeFilter(filter.c_str());
  layer.ResetReading();
  std::vector<ArchivedRun> runs;
  while (std::unique_ptr<OGRFeature> f{layer.GetNextFeature()}) runs.push_back(RunOf(*f));
  layer.SetAttributeFilter(nullptr);
  std::sort(runs.begin(), runs.end(), [](const ArchivedRun& a, const ArchivedRun& b) {
    return std::tie(a.start_time, a.bed, a.run_id) < std::tie(b.start_time, b.bed, b.run_id);
  });
  return runs;
}

PlantSighting SightingOf(const OGRFeature& f) {
  PlantSighting s;
  s.run_id = f.GetFieldAsString("run_id");
  s.bed = f.GetFieldAsInteger("bed");
  s.plant_id = f.GetFieldAsInteger64("plant_id");
  s.cls = f.GetFieldAsString("class");
  s.why = f.GetFieldAsString("why");
  s.radius_m = f.GetFieldAsDouble("radius_m");
  s.treated = f.GetFieldAsInteger("treated") != 0;
  return s;
}

void Copy(GDALDataset& out, OGRLayer& src, const char* name, const std::string& where) {
  OGRLayer* copied = out.CopyLayer(&src, name);
  if (copied == nullptr) ThrowGdal(where, std::string("cannot copy table ") + name);
}

// A query's result as a point layer (a result's geometry type is unknown to GDAL).
void CopyPoints(GDALDataset& out, OGRLayer& src, const char* name, const std::string& where) {
  OGRSpatialReference wgs84 = Wgs84Srs();
  OGRLayer* layer = out.CreateLayer(name, &wgs84, wkbPoint, nullptr);
  if (layer == nullptr) ThrowGdal(where, std::string("cannot create table ") + name);
  OGRFeatureDefn* defn = src.GetLayerDefn();
  for (int i = 0; i < defn->GetFieldCount(); ++i) {
    if (layer->CreateField(defn->GetFieldDefn(i)) != OGRERR_NONE) ThrowGdal(where, std::string("cannot copy ") + name);
  }
  src.ResetReading();
  while (std::unique_ptr<OGRFeature> f{src.GetNextFeature()}) {
    OGRFeature copy(layer->GetLayerDefn());
    copy.SetFrom(f.get());
    if (layer->CreateFeature(&copy) != OGRERR_NONE) ThrowGdal(where, std::string("cannot copy ") + name);
  }
}

std::string SafeFileName(const std::string& field) {
  std::string out;
  for (char c : field) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.empty() ? "field" : out;
}

}  // namespace

std::vector<ArchivedRun> QueryRuns(const std::string& target, const std::string& field,
                                   const std::string& from, const std::string& to) {
  CheckDate(from, "from");
  CheckDate(to, "to");
  GdalErrorScope scope;
  ArchiveDb db = OpenArchive(target, false);
  std::string filter = "field = " + SqlLiteral(field);
  if (!from.empty() || !to.empty()) filter += " AND start_time <> ''";  // runs of unknown time: no date
  if (!from.empty()) filter += " AND start_time >= " + SqlLiteral(from);
  // "YYYY-MM-DDZ" sorts after every "YYYY-MM-DDThh:mm:ssZ" of that day.
  if (!to.empty()) filter += " AND start_time <= " + SqlLiteral(to + "Z");
  return ReadRuns(Table(db, "runs"), filter);
}

PlantHistory QueryPlant(const std::string& target, int64_t season_id) {
  GdalErrorScope scope;
  ArchiveDb db = OpenArchive(target, false);
  std::unique_ptr<OGRFeature> s(Table(db, "season_plants").GetFeature(season_id));
  if (!s) throw InvalidOptionsError("archive plant", {{"ID", "no plant " + std::to_string(season_id) + " in the archive"}});
  PlantHistory h;
  h.season_id = season_id;
  h.field = s->GetFieldAsString("field");
  h.cls = s->GetFieldAsString("class");
  h.first_run = s->GetFieldAsString("first_run");
  h.field_x_m = s->GetFieldAsDouble("field_x_m");
  h.field_y_m = s->GetFieldAsDouble("field_y_m");
  if (const OGRPoint* p = s->GetGeometryRef() ? s->GetGeometryRef()->toPoint() : nullptr) {
    h.lon_deg = p->getX(), h.lat_deg = p->getY();
  }
  OGRLayer& plants = Table(db, "plants");
  plants.SetAttributeFilter(("season_id = " + std::to_string(season_id)).c_str());
  plants.ResetReading();
  std::string runs_filter;
  while (std::unique_ptr<OGRFeature> f{plants.GetNextFeature()}) {
    h.sightings.push_back(SightingOf(*f));
    runs_filter += (runs_filter.empty() ? "" : ", ") + SqlLiteral(h.sightings.back().run_id);
  }
  plants.SetAttributeFilter(nullptr);
  std::map<std::string, ArchivedRun> runs;
  if (!runs_filter.empty()) {
    for (ArchivedRun& r : ReadRuns(Table(db, "runs"), "run_id IN (" + runs_filter + ")")) runs[r.run_id] = r;
  }
  for (PlantSighting& x : h.sightings) {
    x.start_time = runs[x.run_id].start_time;
    x.vehicle = runs[x.run_id].vehicle;
    h.times_treated += x.treated ? 1 : 0;
  }
  std::sort(h.sightings.begin(), h.sightings.end(), [](const PlantSighting& a, const PlantSighting& b) {
    return std::tie(a.start_time, a.run_id) < std::tie(b.start_time, b.run_id);
  });
  return h;
}

std::filesystem::path ExportSeason(const std::string& target, const std::string& field,
                                   const std::filesystem::path& dir) {
  GdalErrorScope scope;
  ArchiveDb db = OpenArchive(target, false);
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / (SafeFileName(field) + ".gpkg");
  const std::string where = "field = " + SqlLiteral(field);
  if (ReadRuns(Table(db, "runs"), where).empty()) {
    throw InvalidOptionsError("archive export", {{"field", "no runs of field '" + field + "' in " + db.name}});
  }
  MemoryFile mem(file);
  DatasetPtr out = CreateDataset("GPKG", mem);
  for (const std::string& name : ArchiveTables()) {
    if (name == "season_plants") continue;
    OGRLayer& src = Table(db, name);
    src.SetAttributeFilter(where.c_str());
    Copy(*out, src, name.c_str(), file.string());
    src.SetAttributeFilter(nullptr);
  }
  // Season plants with how often they were seen and sprayed.
  const std::string sql =
      "SELECT s.fid AS season_id, s.field, s.class, s.field_x_m, s.field_y_m, s.first_run, "
      "COUNT(p.fid) AS sightings, SUM(CASE WHEN p.treated THEN 1 ELSE 0 END) AS times_treated, s.geom "
      "FROM season_plants s JOIN plants p ON p.season_id = s.fid WHERE s." + where +
      " GROUP BY s.fid, s.field, s.class, s.field_x_m, s.field_y_m, s.first_run, s.geom";
  OGRLayer* season = db.ds->ExecuteSQL(sql.c_str(), nullptr, nullptr);
  if (season == nullptr) ThrowGdal(db.name, "cannot read the season's plants");
  CopyPoints(*out, *season, "season_plants", file.string());
  db.ds->ReleaseResultSet(season);
  CloseAndCopy(out, mem);
  return file;
}

}  // namespace plantscale::maps
