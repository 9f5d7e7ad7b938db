#pragma once
// Georeference: anchors the field frame to WGS84 and maps it into the
// projected CRS of the exports (GDAL/OSR; OSR types stay in georef.cc).
//
// Definition (docs/design.md §3, docs/cli/export.md "Georeferencing"):
//  * origin (latitude_deg, longitude_deg), WGS84, is field point (0, 0);
//  * heading_deg is the direction of the field +y axis (along the rows),
//    clockwise from TRUE north at the origin; +x is 90° clockwise from +y;
//  * the plane of the field frame is the transverse Mercator projection
//    centred on the origin (+proj=tmerc +lat_0 +lon_0 +k=1, WGS84), rotated
//    by the heading:  E = x cos h + y sin h,  N = −x sin h + y cos h.
//    It is conformal and true to scale at the origin (scale error below
//    1e-8 within 1 km), so field metres are ground metres.
//  * exports use `epsg` (projected, metres), or when 0 the WGS84 UTM zone of
//    the origin (326zz north, 327zz south; Norway and Svalbard exceptions).

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "maps/map_grid.h"

namespace plantscale::maps {

struct GeoAnchorOptions {
  double latitude_deg = 0.0;   // [-90, 90]; UTM (epsg 0) needs [-80, 84]
  double longitude_deg = 0.0;  // [-180, 180]
  double heading_deg = 0.0;    // [-360, 360]
  int epsg = 0;                // projected CRS of the exports; 0: UTM zone of the origin

  OptionErrors Validate() const;  // ranges only; the EPSG code is checked by Georeference
};

// EPSG code of the WGS84 UTM zone containing (lat, lon).
int UtmEpsg(double latitude_deg, double longitude_deg);

class Georeference {
 public:
  // Throws InvalidOptionsError for bad ranges, an unknown EPSG code or a CRS
  // that is not projected (key "epsg").
  explicit Georeference(const GeoAnchorOptions& options);
  ~Georeference();
  Georeference(Georeference&&) noexcept;
  Georeference& operator=(Georeference&&) noexcept;

  const GeoAnchorOptions& options() const { return options_; }
  int epsg() const { return epsg_; }
  std::string ProjectedWkt() const;  // WKT of the export CRS
  std::string ProjectedName() const;

  Eigen::Vector2d FieldToLocal(const Eigen::Vector2d& field_m) const;  // (E, N) local tmerc
  Eigen::Vector2d LocalToField(const Eigen::Vector2d& local_m) const;
  Eigen::Vector2d FieldToProjected(const Eigen::Vector2d& field_m) const;  // (E, N), metres
  Eigen::Vector2d FieldToWgs84(const Eigen::Vector2d& field_m) const;      // (lon, lat), deg
  Eigen::Vector2d Wgs84ToField(const Eigen::Vector2d& lon_lat_deg) const;
  // Batch form (one PROJ call) for grids of points.
  std::vector<Eigen::Vector2d> Wgs84ToField(const std::vector<Eigen::Vector2d>& lon_lat_deg) const;

  // GDAL geotransform of `grid` as a raster whose first line is the grid's
  // LAST row (largest y, "forward is up") and first column its column 0:
  // projected = GT[0] + P·GT[1] + L·GT[2], GT[3] + P·GT[4] + L·GT[5]. It is the
  // affine map through three exact corners; `max_error_m` (optional) gets its
  // largest distance from the exact transform over the grid's corners and centre.
  std::array<double, 6> GeoTransform(const MapGrid& grid, double* max_error_m = nullptr) const;

 private:
  struct Impl;
  GeoAnchorOptions options_;
  int epsg_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace plantscale::maps
