#include "maps/archive_db.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <regex>

#include "maps/archive.h"
#include "maps/gdal_util.h"
#include "maps/map_errors.h"

namespace plantscale::maps {
namespace {

struct FieldSpec {
  const char* name;
  OGRFieldType type;
};

struct TableSpec {
  OGRwkbGeometryType geometry;
  std::vector<FieldSpec> fields;
  std::vector<std::string> indexes;  // column lists
};

const std::map<std::string, TableSpec>& Specs() {
  static const std::map<std::string, TableSpec> specs{
      {"fields",
       {wkbNone,
        {{"field", OFTString}, {"origin_lat_deg", OFTReal}, {"origin_lon_deg", OFTReal},
         {"heading_deg", OFTReal}, {"epsg", OFTInteger}},
        {"field"}}},
      {"runs",
       {wkbNone,
        {{"run_id", OFTString}, {"field", OFTString}, {"bed", OFTInteger}, {"vehicle", OFTString},
         {"crop_profile", OFTString}, {"source", OFTString}, {"start_time", OFTString},
         {"end_time", OFTString}, {"distance_m", OFTReal}, {"plants", OFTInteger},
         {"crop", OFTInteger}, {"plants_per_m", OFTReal}, {"gaps", OFTInteger},
         {"missing", OFTInteger}, {"median_radius_m", OFTReal}, {"weeds", OFTInteger},
         {"weeds_per_m2", OFTReal}, {"area_treated_m2", OFTReal}, {"treated_plants", OFTInteger},
         {"origin_lat_deg", OFTReal}, {"origin_lon_deg", OFTReal}, {"heading_deg", OFTReal},
         {"exported_at", OFTString}},
        {"run_id", "field, start_time"}}},
      {"season_plants",
       {wkbPoint,
        {{"field", OFTString}, {"class", OFTString}, {"field_x_m", OFTReal},
         {"field_y_m", OFTReal}, {"first_run", OFTString}},
        {"field", "first_run"}}},
      {"plants",
       {wkbPoint,
        {{"run_id", OFTString}, {"field", OFTString}, {"bed", OFTInteger},
         {"season_id", OFTInteger64}},
        {"run_id", "season_id", "field"}}},
      {"rows",
       {wkbLineString,
        {{"run_id", OFTString}, {"field", OFTString}, {"bed", OFTInteger}, {"row", OFTInteger},
         {"crop", OFTInteger}, {"length_m", OFTReal}, {"plants_per_m", OFTReal},
         {"gaps", OFTInteger}, {"missing", OFTInteger}, {"median_radius_m", OFTReal},
         {"weeds", OFTInteger}, {"weeds_per_m2", OFTReal}},
        {"run_id"}}},
      {"treated_areas",
       {wkbPolygon,
        {{"run_id", OFTString}, {"field", OFTString}, {"bed", OFTInteger}, {"area_m2", OFTReal}},
        {"run_id"}}},
      {"map_tiles",
       {wkbPolygon,
        {{"run_id", OFTString}, {"field", OFTString}, {"bed", OFTInteger},
         {"tile_col", OFTInteger}, {"tile_row", OFTInteger}, {"cols", OFTInteger},
         {"rows", OFTInteger}, {"resolution_m", OFTReal}, {"x0_m", OFTReal}, {"y0_m", OFTReal},
         {"cells", OFTBinary}},
        {"run_id"}}},
  };
  return specs;
}

void AddFields(OGRLayer& layer, const std::string& name, const TableSpec& spec,
               const std::string& where) {
  if (name == "plants") AddPlantFields(layer, where);  // the GeoPackage export's plant columns
  for (const FieldSpec& f : spec.fields) {
    OGRFieldDefn defn(f.name, f.type);
    if (layer.CreateField(&defn) != OGRERR_NONE) {
      ThrowGdal(where, "cannot add column " + name + "." + f.name);
    }
  }
}

void CreateIndexes(ArchiveDb& db, const std::string& name, const TableSpec& spec) {
  for (const std::string& columns : spec.indexes) {
    std::string index = name + "_by_" + columns;
    for (char& c : index) c = (c == ',' || c == ' ') ? '_' : c;
    ExecuteSql(db, "CREATE INDEX IF NOT EXISTS " + index + " ON " + name + " (" + columns + ")");
  }
}

void CheckPostgis(ArchiveDb& db) {
  OGRLayer* r = db.ds->ExecuteSQL("SELECT postgis_lib_version()", nullptr, nullptr);
  if (r != nullptr) db.ds->ReleaseResultSet(r);
  if (r == nullptr) {
    throw MapIoError(db.name,
                     "the database has no PostGIS (run CREATE EXTENSION postgis in it as its owner)");
  }
}

}  // namespace

FileLock::FileLock(const std::string& path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw MapIoError(path, std::string("cannot open the lock file: ") + std::strerror(errno));
  while (::flock(fd_, LOCK_EX) != 0) {
    if (errno != EINTR) throw MapIoError(path, std::string("cannot lock: ") + std::strerror(errno));
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

bool IsPostgresTarget(const std::string& target) {
  return target.rfind("postgresql://", 0) == 0 || target.rfind("postgres://", 0) == 0 ||
         target.rfind("PG:", 0) == 0;
}

std::string Redacted(const std::string& target) {
  static const std::regex url(R"(^(postgres(ql)?://[^:/@]*:)[^@]*@)");
  static const std::regex key(R"((password\s*=\s*)('[^']*'|\S+))");
  std::string out = std::regex_replace(target, url, "$1***@");
  return std::regex_replace(out, key, "$1***");
}

ArchiveDb OpenArchive(const std::string& target, bool create) {
  EnsureGdalRegistered();
  ArchiveDb db;
  db.name = Redacted(target);
  db.postgres = IsPostgresTarget(target);
  if (!db.postgres) {
    if (create) db.lock = std::make_unique<FileLock>(target + ".lock");
    if (!std::filesystem::exists(target)) {
      if (!create) throw MapIoError(target, "no such archive");
      GDALDriver* gpkg = GetGDALDriverManager()->GetDriverByName("GPKG");
      db.ds.reset(gpkg->Create(target.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
      if (!db.ds) ThrowGdal(target, "cannot create the GeoPackage archive");
      return db;
    }
  }
  const char* drivers[] = {db.postgres ? "PostgreSQL" : "GPKG", nullptr};
  db.ds.reset(GDALDataset::FromHandle(GDALOpenEx(
      target.c_str(), GDAL_OF_VECTOR | GDAL_OF_UPDATE, drivers, nullptr, nullptr)));
  if (!db.ds) {
    ThrowGdal(db.name, db.postgres ? "cannot connect to the archive database"
                                   : "cannot open the GeoPackage archive");
  }
  if (db.postgres) CheckPostgis(db);
  return db;
}

std::string SqlLiteral(const std::string& text) {
  if (text.find('\0') != std::string::npos) {
    throw InvalidOptionsError("archive", {{"text", "holds a NUL byte"}});
  }
  std::string out = "'";
  for (char c : text) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

void ExecuteSql(ArchiveDb& db, const std::string& sql) {
  CPLErrorReset();
  OGRLayer* r = db.ds->ExecuteSQL(sql.c_str(), nullptr, nullptr);
  if (r != nullptr) db.ds->ReleaseResultSet(r);
  if (CPLGetLastErrorType() == CE_Failure || CPLGetLastErrorType() == CE_Fatal) {
    ThrowGdal(db.name, "SQL failed: " + sql.substr(0, 120));
  }
}

std::optional<int64_t> QueryInt(ArchiveDb& db, const std::string& sql) {
  CPLErrorReset();
  OGRLayer* r = db.ds->ExecuteSQL(sql.c_str(), nullptr, nullptr);
  if (r == nullptr) ThrowGdal(db.name, "SQL failed: " + sql.substr(0, 120));
  std::optional<int64_t> value;
  std::unique_ptr<OGRFeature> f(r->GetNextFeature());
  if (f && f->IsFieldSetAndNotNull(0)) value = f->GetFieldAsInteger64(0);
  db.ds->ReleaseResultSet(r);
  return value;
}

const std::vector<std::string>& ArchiveTables() {
  static const std::vector<std::string> names{"fields", "runs", "season_plants", "plants",
                                              "rows", "treated_areas", "map_tiles"};
  return names;
}

OGRLayer* FindTable(ArchiveDb& db, const std::string& name) {
  CPLErrorReset();
  OGRLayer* layer = db.ds->GetLayerByName(name.c_str());
  CPLErrorReset();  // a missing table is not a failure
  return layer;
}

OGRLayer& EnsureTable(ArchiveDb& db, const std::string& name) {
  if (OGRLayer* layer = FindTable(db, name)) return *layer;
  const TableSpec& spec = Specs().at(name);
  OGRSpatialReference wgs84 = Wgs84Srs();
  CPLStringList opts;
  opts.AddString("FID=fid");
  if (spec.geometry != wkbNone) opts.AddString("GEOMETRY_NAME=geom");
  if (db.postgres) opts.AddString("PRECISION=NO");
  OGRLayer* layer = db.ds->CreateLayer(name.c_str(), spec.geometry == wkbNone ? nullptr : &wgs84,
                                       spec.geometry, opts.List());
  if (layer == nullptr) ThrowGdal(db.name, "cannot create table " + name);
  AddFields(*layer, name, spec, db.name);
  CreateIndexes(db, name, spec);
  return *layer;
}

}  // namespace plantscale::maps
