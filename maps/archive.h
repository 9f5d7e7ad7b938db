#pragma once
// The season archive (issue 37, docs/archive.md): every run of every field
// in one place, a PostgreSQL/PostGIS database (postgresql://…) or a
// GeoPackage file, written and read through GDAL's vector drivers, the same
// writer code for both.
//
// Tables (one schema for both targets; geometries in WGS84, EPSG:4326):
//   fields         field, origin_lat_deg, origin_lon_deg, heading_deg: the
//                  field frame of the field (set by its first run)
//   runs           one row per run: run_id, field, bed, vehicle, crop
//                  profile, start/end time, distance and the run's figures
//   season_plants  points: one plant over the season (fid = season id)
//   plants         points: one plant seen in one run (per-run plant_id,
//                  season_id, class, size, why sprayed)
//   rows           lines: each crop row's stand in the run, with its figures
//   treated_areas  polygons: the run's treated cells
//   map_tiles      polygons: 256 × 256 cells of the run's class map, cells
//                  as bytes (class 0 soil, 1 crop, 2 weed, 3 unknown; +4 treated)
//
// An append is ONE transaction: the run's old rows (same run_id) are
// deleted and the new ones written, so a reader sees the whole run or none of
// it, a re-export replaces and a killed export leaves nothing. Appends are
// serialised (PostgreSQL: an advisory transaction lock; GeoPackage: a lock
// file beside it), so concurrent exports lose and duplicate nothing.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "maps/crop_map.h"
#include "maps/georef.h"

namespace plantscale::maps {

// A run's agronomic figures (computed by the caller, review/agronomy.h definitions).
struct ArchiveRowFigures {
  int row = 0;
  int crop = 0;
  double stand_y0_m = 0.0, stand_y1_m = 0.0;  // along the row (field frame)
  double x_m = 0.0;                           // across (field frame)
  double plants_per_m = 0.0;
  int gaps = 0, missing = 0;
  double median_radius_m = 0.0;
  int weeds = 0;
  double weeds_per_m2 = 0.0;
};

struct ArchiveFigures {
  int crop = 0;
  double plants_per_m = 0.0;
  int gaps = 0, missing = 0;
  double median_radius_m = 0.0;  // crop leaf-tip radius
  int weeds = 0;
  double weeds_per_m2 = 0.0;
  double area_treated_m2 = 0.0;  // filled by the archive: treated cells × cell area
  int treated_plants = 0;        // filled by the archive
  std::vector<ArchiveRowFigures> rows;
};

struct ArchiveRun {
  std::string run_id;  // stable for a given log: re-exporting replaces
  std::string field;
  int bed = 0;
  std::string vehicle, crop_profile, source;  // source: the log's file name
  std::string start_time, end_time;           // ISO 8601 UTC, "" when unknown
  double distance_m = 0.0;
  ArchiveFigures figures;
};

struct ArchiveOptions {
  // Plants of one field and class closer than this in two runs are one plant
  // (after aligning the run to the season, below).
  double match_tolerance_m = 0.05;
  // A run is first shifted by the median offset of its crops to the season's
  // crops within this radius (0: no alignment). Below half the smallest plant
  // spacing (30 cm, lettuce) so that a pair is one plant.
  double align_radius_m = 0.12;
  OptionErrors Validate() const;
};

struct AppendResult {
  bool replaced = false;  // the run was in the archive before
  int plants = 0, matched = 0, new_plants = 0;
  Eigen::Vector2d offset_m{0.0, 0.0};  // the run's shift onto the season's frame
  std::string field_origin;  // "lat,lon heading" the field frame used
};

// True for postgresql://, postgres:// and PG: targets.
bool IsPostgresTarget(const std::string& target);
// The target with any password replaced by ***, for messages.
std::string Redacted(const std::string& target);

// Appends (or replaces) `run` in the archive at `target` (created when a
// GeoPackage path does not exist). `anchor` georeferences the map; when
// absent, the field's stored frame is used. Throws InvalidOptionsError (no
// anchor for a new field, bad options, a run of no plants), MapIoError
// naming the (redacted) target: refused connection, bad password, no
// PostGIS, write failure. On any throw the archive is unchanged.
AppendResult AppendRun(const std::string& target, const ArchiveRun& run, const CropMap& map,
                       const std::optional<GeoAnchorOptions>& anchor,
                       const ArchiveOptions& options = {});

// A stored run (its figures without rows).
using ArchivedRun = ArchiveRun;

// Runs of `field` whose start time lies in [from, to] (dates YYYY-MM-DD, or
// empty for open; runs of unknown start time only when both are open),
// oldest first.
std::vector<ArchivedRun> QueryRuns(const std::string& target, const std::string& field,
                                   const std::string& from = "", const std::string& to = "");

struct PlantSighting {
  std::string run_id, start_time, vehicle;
  int bed = 0;
  int64_t plant_id = 0;  // per-run id
  std::string cls, why;
  double radius_m = 0.0;
  bool treated = false;
};

struct PlantHistory {
  int64_t season_id = 0;
  std::string field, cls, first_run;
  double lon_deg = 0.0, lat_deg = 0.0, field_x_m = 0.0, field_y_m = 0.0;
  std::vector<PlantSighting> sightings;  // oldest first
  int times_treated = 0;
};

// Throws InvalidOptionsError when no plant has `season_id`.
PlantHistory QueryPlant(const std::string& target, int64_t season_id);

// Writes DIR/<field>.gpkg: the archive's tables restricted to `field`, plus
// season_plants with their sightings and times treated. Returns the file.
std::filesystem::path ExportSeason(const std::string& target, const std::string& field,
                                   const std::filesystem::path& dir);

}  // namespace plantscale::maps
