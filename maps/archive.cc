// AppendRun: one run into the archive in one transaction (archive.h).
#include "maps/archive.h"

#include <gdal_alg.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <unordered_map>

#include "maps/archive_db.h"
#include "maps/export.h"
#include "maps/gdal_util.h"
#include "maps/map_errors.h"
#include "maps/writers.h"

namespace plantscale::maps {
namespace {

constexpr int kTileCells = 256;
constexpr int64_t kArchiveLock = 0x70736172;  // "psar": the advisory lock of appends

struct SeasonPlant {
  int64_t id = 0;
  PlantKind kind = PlantKind::kUnknown;
  Eigen::Vector2d xy;  // field frame of the field
};

std::string Utc(std::time_t t) {
  char buf[32];
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string FieldFilter(const std::string& field) { return "field = " + SqlLiteral(field); }

std::optional<GeoAnchorOptions> StoredFieldAnchor(ArchiveDb& db, const std::string& field) {
  OGRLayer& fields = EnsureTable(db, "fields");
  fields.SetAttributeFilter(FieldFilter(field).c_str());
  fields.ResetReading();
  std::unique_ptr<OGRFeature> f(fields.GetNextFeature());
  fields.SetAttributeFilter(nullptr);
  if (!f) return std::nullopt;
  GeoAnchorOptions a;
  a.latitude_deg = f->GetFieldAsDouble("origin_lat_deg");
  a.longitude_deg = f->GetFieldAsDouble("origin_lon_deg");
  a.heading_deg = f->GetFieldAsDouble("heading_deg");
  a.epsg = f->GetFieldAsInteger("epsg");
  return a;
}

void Create(ArchiveDb& db, OGRLayer& layer, OGRFeature& f) {
  if (layer.CreateFeature(&f) != OGRERR_NONE) {
    ThrowGdal(db.name, std::string("cannot write to table ") + layer.GetName());
  }
}

void StoreField(ArchiveDb& db, const std::string& field, const GeoAnchorOptions& a) {
  OGRLayer& fields = EnsureTable(db, "fields");
  OGRFeature f(fields.GetLayerDefn());
  f.SetField("field", field.c_str());
  f.SetField("origin_lat_deg", a.latitude_deg);
  f.SetField("origin_lon_deg", a.longitude_deg);
  f.SetField("heading_deg", a.heading_deg);
  f.SetField("epsg", a.epsg);
  Create(db, fields, f);
}

void DeleteRun(ArchiveDb& db, const std::string& run_id) {
  const std::string id = SqlLiteral(run_id);
  for (const char* table : {"plants", "rows", "treated_areas", "map_tiles", "runs"}) {
    ExecuteSql(db, std::string("DELETE FROM ") + table + " WHERE run_id = " + id);
  }
}

// After a replacement: plants first seen in the replaced run and seen in no run now.
void DeleteOrphans(ArchiveDb& db, const std::string& run_id) {
  ExecuteSql(db, "DELETE FROM season_plants WHERE first_run = " + SqlLiteral(run_id) +
                     " AND NOT EXISTS (SELECT 1 FROM plants p WHERE p.season_id = season_plants.fid)");
}

std::vector<SeasonPlant> SeasonPlantsOf(ArchiveDb& db, const std::string& field) {
  OGRLayer& layer = EnsureTable(db, "season_plants");
  layer.SetAttributeFilter(FieldFilter(field).c_str());
  layer.ResetReading();
  std::vector<SeasonPlant> out;
  while (std::unique_ptr<OGRFeature> f{layer.GetNextFeature()}) {
    out.push_back({f->GetFID(), ParsePlantKind(f->GetFieldAsString("class"), "season_plants.class"),
                   {f->GetFieldAsDouble("field_x_m"), f->GetFieldAsDouble("field_y_m")}});
  }
  layer.SetAttributeFilter(nullptr);
  return out;
}

// Greedy nearest-first matching of the run's plants (field frame) to the
// season's plants of the same class within `tol`: result[i] is the index
// into `season` of plant i, or -1.
std::vector<int> MatchPlants(const std::vector<Eigen::Vector2d>& xy, const std::vector<PlantKind>& kind,
                             const std::vector<SeasonPlant>& season, double tol) {
  const auto key = [tol](const Eigen::Vector2d& p) {
    return std::make_pair(static_cast<int64_t>(std::floor(p.x() / tol)), static_cast<int64_t>(std::floor(p.y() / tol)));
  };
  struct Hash {
    size_t operator()(const std::pair<int64_t, int64_t>& k) const { return std::hash<int64_t>()(k.first * 1000003 ^ k.second); }
  };
  std::unordered_map<std::pair<int64_t, int64_t>, std::vector<int>, Hash> cells;
  for (size_t j = 0; j < season.size(); ++j) cells[key(season[j].xy)].push_back(static_cast<int>(j));
  struct Pair { double d; int i, j; };
  std::vector<Pair> pairs;
  for (size_t i = 0; i < xy.size(); ++i) {
    const auto [cx, cy] = key(xy[i]);
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = cells.find({cx + dx, cy + dy});
        if (it == cells.end()) continue;
        for (int j : it->second) {
          const double d = (season[static_cast<size_t>(j)].xy - xy[i]).norm();
          if (d <= tol && season[static_cast<size_t>(j)].kind == kind[i]) pairs.push_back({d, static_cast<int>(i), j});
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<int> match(xy.size(), -1);
  std::vector<char> taken(season.size(), 0);
  for (const Pair& p : pairs) {
    if (match[static_cast<size_t>(p.i)] >= 0 || taken[static_cast<size_t>(p.j)]) continue;
    match[static_cast<size_t>(p.i)] = p.j;
    taken[static_cast<size_t>(p.j)] = 1;
  }
  return match;
}

struct Frames {
  Georeference run;    // the run's anchor: geometries
  Georeference field;  // the field's anchor: season positions
  bool same = true;
  Eigen::Vector2d ToField(const Eigen::Vector2d& p) const {
    return same ? p : field.Wgs84ToField(run.FieldToWgs84(p));
  }
};

void SetCommon(OGRFeature& f, const ArchiveRun& run) {
  f.SetField("run_id", run.run_id.c_str());
  f.SetField("field", run.field.c_str());
  f.SetField("bed", run.bed);
}

std::unique_ptr<OGRPoint> Point(const Frames& frames, const Eigen::Vector2d& p) {
  const Eigen::Vector2d ll = frames.run.FieldToWgs84(p);
  return std::make_unique<OGRPoint>(ll.x(), ll.y());
}

// How far the run's field frame sits from the season's: the median offset
// from the run's crops to the nearest season crop within `radius` (less than
// half the plant spacing, so each pair is one plant), when at least 10 pairs
// agree; else none. Passes differ by where their frame started (tracker
// initialisation, odometry), a shift common to every plant of the run.
Eigen::Vector2d AlignmentOffset(const std::vector<Eigen::Vector2d>& xy, const std::vector<PlantKind>& kind,
                                const std::vector<SeasonPlant>& season, double radius) {
  std::vector<Eigen::Vector2d> crops;
  std::vector<PlantKind> crop_kind;
  for (size_t i = 0; i < xy.size(); ++i) {
    if (kind[i] == PlantKind::kCrop) crops.push_back(xy[i]), crop_kind.push_back(kind[i]);
  }
  const std::vector<int> match = MatchPlants(crops, crop_kind, season, radius);
  std::vector<double> dx, dy;
  for (size_t i = 0; i < crops.size(); ++i) {
    if (match[i] < 0) continue;
    const Eigen::Vector2d d = season[static_cast<size_t>(match[i])].xy - crops[i];
    dx.push_back(d.x()), dy.push_back(d.y());
  }
  if (dx.size() < 10) return Eigen::Vector2d::Zero();
  const auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  return {median(dx), median(dy)};
}

// Season ids of the run's plants: matched or new (written to season_plants).
std::vector<int64_t> SeasonIds(ArchiveDb& db, const ArchiveRun& run, const CropMap& map,
                               const Frames& frames, const ArchiveOptions& o, AppendResult& result) {
  const std::vector<SeasonPlant> season = SeasonPlantsOf(db, run.field);
  std::vector<Eigen::Vector2d> xy;
  std::vector<PlantKind> kind;
  for (const MapPlant& p : map.plants()) xy.push_back(frames.ToField(p.position_m)), kind.push_back(p.kind);
  result.offset_m = AlignmentOffset(xy, kind, season, o.align_radius_m);
  for (Eigen::Vector2d& p : xy) p += result.offset_m;
  const std::vector<int> match = MatchPlants(xy, kind, season, o.match_tolerance_m);
  int64_t next = QueryInt(db, "SELECT MAX(fid) FROM season_plants").value_or(0) + 1;
  OGRLayer& layer = EnsureTable(db, "season_plants");
  std::vector<int64_t> ids(xy.size());
  for (size_t i = 0; i < xy.size(); ++i) {
    if (match[i] >= 0) {
      ids[i] = season[static_cast<size_t>(match[i])].id;
      ++result.matched;
      continue;
    }
    ids[i] = next++;
    OGRFeature f(layer.GetLayerDefn());
    f.SetFID(ids[i]);
    f.SetField("field", run.field.c_str());
    f.SetField("class", ToString(kind[i]));
    f.SetField("field_x_m", xy[i].x());
    f.SetField("field_y_m", xy[i].y());
    f.SetField("first_run", run.run_id.c_str());
    f.SetGeometry(Point(frames, map.plants()[i].position_m).get());
    Create(db, layer, f);
    ++result.new_plants;
  }
  return ids;
}

void WritePlants(ArchiveDb& db, const ArchiveRun& run, const CropMap& map, const Frames& frames,
                 const std::vector<int64_t>& season_ids, const Eigen::Vector2d& offset) {
  OGRLayer& layer = EnsureTable(db, "plants");
  for (size_t i = 0; i < map.plants().size(); ++i) {
    const MapPlant& p = map.plants()[i];
    const Eigen::Vector2d ll = frames.run.FieldToWgs84(p.position_m);
    const Eigen::Vector2d en = frames.run.FieldToProjected(p.position_m);
    const Eigen::Vector2d xy = frames.ToField(p.position_m) + offset;
    OGRFeature f(layer.GetLayerDefn());
    SetCommon(f, run);
    f.SetField("season_id", static_cast<GIntBig>(season_ids[i]));
    f.SetField("plant_id", static_cast<GIntBig>(p.id));
    f.SetField("class", ToString(p.kind));
    f.SetField("confidence", p.confidence);
    f.SetField("radius_m", p.radius_m);
    f.SetField("treated", p.treated ? 1 : 0);
    f.SetField("why", p.why.c_str());
    f.SetField("field_x_m", xy.x());
    f.SetField("field_y_m", xy.y());
    f.SetField("lon_deg", ll.x());
    f.SetField("lat_deg", ll.y());
    f.SetField("easting_m", en.x());
    f.SetField("northing_m", en.y());
    f.SetGeometry(std::make_unique<OGRPoint>(ll.x(), ll.y()).get());
    Create(db, layer, f);
  }
}

void WriteRows(ArchiveDb& db, const ArchiveRun& run, const Frames& frames) {
  OGRLayer& layer = EnsureTable(db, "rows");
  for (const ArchiveRowFigures& r : run.figures.rows) {
    OGRLineString line;
    for (double y : {r.stand_y0_m, r.stand_y1_m}) {
      const Eigen::Vector2d ll = frames.run.FieldToWgs84({r.x_m, y});
      line.addPoint(ll.x(), ll.y());
    }
    OGRFeature f(layer.GetLayerDefn());
    SetCommon(f, run);
    f.SetField("row", r.row);
    f.SetField("crop", r.crop);
    f.SetField("length_m", r.stand_y1_m - r.stand_y0_m);
    f.SetField("plants_per_m", r.plants_per_m);
    f.SetField("gaps", r.gaps);
    f.SetField("missing", r.missing);
    f.SetField("median_radius_m", r.median_radius_m);
    f.SetField("weeds", r.weeds);
    f.SetField("weeds_per_m2", r.weeds_per_m2);
    f.SetGeometry(&line);
    Create(db, layer, f);
  }
}

// Treated cells as polygons: polygonized in the field frame, every vertex
// then taken to WGS84 exactly (no affine approximation).
void WriteTreatedAreas(ArchiveDb& db, const ArchiveRun& run, const CropMap& map, const Frames& frames) {
  const MapGrid& g = map.grid();
  DatasetPtr raster = CreateScratchRaster(g.cols(), g.rows(), 1, GDT_Byte);
  double gt[6] = {g.origin_m().x(), g.resolution_m(), 0.0, g.max_m().y(), 0.0, -g.resolution_m()};
  raster->SetGeoTransform(gt);
  GDALRasterBand* band = raster->GetRasterBand(1);
  WriteTreatedBand(map, *band, db.name);
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("Memory");
  DatasetPtr vec(mem->Create("treated", 0, 0, 0, GDT_Unknown, nullptr));
  OGRLayer* polys = vec->CreateLayer("treated", nullptr, wkbPolygon, nullptr);
  if (GDALPolygonize(GDALRasterBand::ToHandle(band), GDALRasterBand::ToHandle(band), OGRLayer::ToHandle(polys), -1,
                     nullptr, nullptr, nullptr) != CE_None) {
    ThrowGdal(db.name, "cannot polygonize the treated area of run " + run.run_id);
  }
  OGRLayer& layer = EnsureTable(db, "treated_areas");
  polys->ResetReading();
  while (std::unique_ptr<OGRFeature> p{polys->GetNextFeature()}) {
    OGRPolygon* poly = p->GetGeometryRef()->toPolygon();
    const double area = poly->get_Area();
    for (OGRLinearRing* ring : *poly) {
      for (int k = 0; k < ring->getNumPoints(); ++k) {
        const Eigen::Vector2d ll = frames.run.FieldToWgs84({ring->getX(k), ring->getY(k)});
        ring->setPoint(k, ll.x(), ll.y());
      }
    }
    OGRFeature f(layer.GetLayerDefn());
    SetCommon(f, run);
    f.SetField("area_m2", area);
    f.SetGeometry(poly);
    Create(db, layer, f);
  }
}

// One tile's cells (row-major from its smallest y), or nothing when all unknown.
std::optional<std::vector<GByte>> TileCells(const CropMap& map, int c0, int r0, int cols, int rows) {
  const MapGrid& g = map.grid();
  std::vector<GByte> cells(static_cast<size_t>(cols) * static_cast<size_t>(rows));
  bool any = false;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const size_t i = g.Index({c0 + c, r0 + r});
      const uint8_t cls = map.layers().cls[i];
      any = any || cls != static_cast<uint8_t>(CellClass::kUnknown);
      cells[static_cast<size_t>(r) * static_cast<size_t>(cols) + static_cast<size_t>(c)] =
          static_cast<GByte>(cls | (map.layers().treated[i] == 1 ? 4 : 0));
    }
  }
  if (!any) return std::nullopt;
  return cells;
}

void WriteMapTiles(ArchiveDb& db, const ArchiveRun& run, const CropMap& map, const Frames& frames) {
  const MapGrid& g = map.grid();
  OGRLayer& layer = EnsureTable(db, "map_tiles");
  for (int r0 = 0; r0 < g.rows(); r0 += kTileCells) {
    for (int c0 = 0; c0 < g.cols(); c0 += kTileCells) {
      const int cols = std::min(kTileCells, g.cols() - c0), rows = std::min(kTileCells, g.rows() - r0);
      const std::optional<std::vector<GByte>> cells = TileCells(map, c0, r0, cols, rows);
      if (!cells) continue;
      const Eigen::Vector2d lo = g.CellCorner({c0, r0});
      const Eigen::Vector2d hi = lo + g.resolution_m() * Eigen::Vector2d(cols, rows);
      OGRLinearRing ring;
      for (const Eigen::Vector2d& p : {lo, Eigen::Vector2d(hi.x(), lo.y()), hi, Eigen::Vector2d(lo.x(), hi.y()), lo}) {
        const Eigen::Vector2d ll = frames.run.FieldToWgs84(p);
        ring.addPoint(ll.x(), ll.y());
      }
      OGRPolygon poly;
      poly.addRing(&ring);
      OGRFeature f(layer.GetLayerDefn());
      SetCommon(f, run);
      f.SetField("tile_col", c0 / kTileCells);
      f.SetField("tile_row", r0 / kTileCells);
      f.SetField("cols", cols);
      f.SetField("rows", rows);
      f.SetField("resolution_m", g.resolution_m());
      f.SetField("x0_m", lo.x());
      f.SetField("y0_m", lo.y());
      f.SetField(f.GetFieldIndex("cells"), static_cast<int>(cells->size()), cells->data());
      f.SetGeometry(&poly);
      Create(db, layer, f);
    }
  }
}

void WriteRunRow(ArchiveDb& db, const ArchiveRun& run, const CropMap& map, const GeoAnchorOptions& a) {
  OGRLayer& layer = EnsureTable(db, "runs");
  const ArchiveFigures& fig = run.figures;
  OGRFeature f(layer.GetLayerDefn());
  SetCommon(f, run);
  for (const auto& [k, v] : {std::pair{"vehicle", &run.vehicle}, {"crop_profile", &run.crop_profile},
                             {"source", &run.source}, {"start_time", &run.start_time}, {"end_time", &run.end_time}}) {
    f.SetField(k, v->c_str());
  }
  f.SetField("distance_m", run.distance_m);
  f.SetField("plants", static_cast<int>(map.plants().size()));
  f.SetField("crop", fig.crop);
  f.SetField("plants_per_m", fig.plants_per_m);
  f.SetField("gaps", fig.gaps);
  f.SetField("missing", fig.missing);
  f.SetField("median_radius_m", fig.median_radius_m);
  f.SetField("weeds", fig.weeds);
  f.SetField("weeds_per_m2", fig.weeds_per_m2);
  const double cell = map.grid().resolution_m() * map.grid().resolution_m();
  f.SetField("area_treated_m2", static_cast<double>(map.treated_cells()) * cell);
  f.SetField("treated_plants", static_cast<int>(std::count_if(map.plants().begin(), map.plants().end(),
                                                              [](const MapPlant& p) { return p.treated; })));
  f.SetField("origin_lat_deg", a.latitude_deg);
  f.SetField("origin_lon_deg", a.longitude_deg);
  f.SetField("heading_deg", a.heading_deg);
  f.SetField("exported_at", Utc(std::time(nullptr)).c_str());
  Create(db, layer, f);
}

void Lock(ArchiveDb& db) {
  if (!db.postgres) return;  // the GeoPackage's lock file is held since it was opened
  const std::optional<int64_t> got = QueryInt(db, "SELECT 1 FROM (SELECT pg_advisory_xact_lock(" +
                                                      std::to_string(kArchiveLock) + ")) AS l");
  if (!got) ThrowGdal(db.name, "cannot take the archive's append lock");
}

void CheckRun(const ArchiveRun& run, const CropMap& map, const ArchiveOptions& options) {
  ThrowIfInvalid("archive options", options.Validate());
  OptionErrors e;
  if (run.field.empty()) e.push_back({"field", "empty field name"});
  if (run.run_id.empty()) e.push_back({"run_id", "empty run id"});
  if (map.plants().empty()) e.push_back({"plants", "the run holds no plants: nothing to archive"});
  ThrowIfInvalid("archive run", e);
  SqlLiteral(run.field);  // no NUL byte
}

}  // namespace

OptionErrors ArchiveOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "match_tolerance_m", match_tolerance_m, 1e-4, 1.0);
  RequireInRange(e, "align_radius_m", align_radius_m, 0.0, 1.0);
  return e;
}

AppendResult AppendRun(const std::string& target, const ArchiveRun& run, const CropMap& map,
                       const std::optional<GeoAnchorOptions>& anchor, const ArchiveOptions& options) {
  CheckRun(run, map, options);
  GdalErrorScope scope;
  CPLConfigOptionSetter copy("PG_USE_COPY", "YES", true);
  ArchiveDb db = OpenArchive(target, true);
  if (db.ds->StartTransaction(TRUE) != OGRERR_NONE) ThrowGdal(db.name, "cannot start a transaction");
  try {
    Lock(db);
    AppendResult result;
    for (const std::string& t : ArchiveTables()) EnsureTable(db, t);
    const std::optional<GeoAnchorOptions> stored = StoredFieldAnchor(db, run.field);
    if (!anchor && !stored) {
      throw InvalidOptionsError("archive", {{"anchor", "field '" + run.field +
                                                           "' is new to the archive: give its origin (--origin LAT,LON)"}});
    }
    if (!stored) StoreField(db, run.field, *anchor);
    const GeoAnchorOptions field_anchor = stored ? *stored : *anchor;
    const GeoAnchorOptions run_anchor = anchor ? *anchor : *stored;
    Frames frames{Georeference(run_anchor), Georeference(field_anchor),
                  run_anchor.latitude_deg == field_anchor.latitude_deg &&
                      run_anchor.longitude_deg == field_anchor.longitude_deg &&
                      run_anchor.heading_deg == field_anchor.heading_deg};
    result.replaced = QueryInt(db, "SELECT COUNT(*) FROM runs WHERE run_id = " + SqlLiteral(run.run_id)).value_or(0) > 0;
    DeleteRun(db, run.run_id);
    const std::vector<int64_t> ids = SeasonIds(db, run, map, frames, options, result);
    WritePlants(db, run, map, frames, ids, result.offset_m);
    if (result.replaced) DeleteOrphans(db, run.run_id);
    WriteRows(db, run, frames);
    WriteTreatedAreas(db, run, map, frames);
    WriteMapTiles(db, run, map, frames);
    WriteRunRow(db, run, map, run_anchor);
    if (db.ds->CommitTransaction() != OGRERR_NONE) ThrowGdal(db.name, "cannot commit the run");
    result.plants = static_cast<int>(map.plants().size());
    result.field_origin = ExactText(field_anchor.latitude_deg) + "," + ExactText(field_anchor.longitude_deg) +
                          " heading " + ExactText(field_anchor.heading_deg);
    return result;
  } catch (...) {
    db.ds->RollbackTransaction();
    throw;
  }
}

}  // namespace plantscale::maps
