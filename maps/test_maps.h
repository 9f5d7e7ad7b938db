#pragma once
// Test fixtures for maps_test: a small synthetic map with known plants, a
// fresh temporary folder, and the independent expectation of where a field
// point lands (geodesic from the origin, then OSR WGS84 → projected).

#include <geodesic.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>

#include "maps/crop_map.h"
#include "maps/georef.h"

namespace plantscale::maps::testing {

// Map 2 m × 6 m at 2 cm; plants: crops on rows x = −0.45, 0, 0.45 every
// 0.5 m (ids 1..), one treated weed (id 1000) at (0.21, 2.11), a cell centre, one unknown (1001).
inline CropMap SyntheticMap() {
  CropMap map(MapGrid({0.02, {-1.0, -0.5}, 100, 300}));
  map.MarkObserved({-1.0, -0.5}, {1.0, 5.5});
  int64_t id = 1;
  for (int n = -1; n <= 1; ++n) {
    MapRow row{n, {}};
    for (int m = 0; m < 10; ++m) {
      const Eigen::Vector2d p(0.45 * n, 0.5 * m);
      map.AddPlant({id++, p, PlantKind::kCrop, 0.9, 0.08, false, "crop"});
      row.points_m.push_back(p);
    }
    map.AddRow(row);
  }
  map.AddPlant({1000, {0.21, 2.11}, PlantKind::kWeed, 0.75, 0.03, true, "weed in row gap"});
  map.AddPlant({1001, {-0.7, 4.33}, PlantKind::kUnknown, 0.4, 0.01, false, "too small"});
  map.SetMetadata("source", "synthetic test map");
  return map;
}

inline GeoAnchorOptions TestAnchor(double heading_deg = 30.0, int epsg = 0) {
  GeoAnchorOptions a;
  a.latitude_deg = 52.0;
  a.longitude_deg = -0.4;
  a.heading_deg = heading_deg;
  a.epsg = epsg;
  return a;
}

// WGS84 (lon, lat) of field point p, computed independently of Georeference:
// the geodesic from the origin with azimuth heading + atan2(x, y) and length
// |p| (GeographicLib's algorithm in PROJ's geodesic.h). It differs from the
// local transverse Mercator plane by < 1e-8 m within 100 m.
inline Eigen::Vector2d GeodesicLonLat(const GeoAnchorOptions& a, const Eigen::Vector2d& p) {
  geod_geodesic g;
  geod_init(&g, 6378137.0, 1 / 298.257223563);
  const double azimuth = a.heading_deg + std::atan2(p.x(), p.y()) * 180.0 / std::numbers::pi;
  double lat = 0.0, lon = 0.0, azi2 = 0.0;
  geod_direct(&g, a.latitude_deg, a.longitude_deg, azimuth, p.norm(), &lat, &lon, &azi2);
  return {lon, lat};
}

inline double GeodesicDistanceM(const Eigen::Vector2d& ll0, const Eigen::Vector2d& ll1) {
  geod_geodesic g;
  geod_init(&g, 6378137.0, 1 / 298.257223563);
  double s = 0.0, a1 = 0.0, a2 = 0.0;
  geod_inverse(&g, ll0.y(), ll0.x(), ll1.y(), ll1.x(), &s, &a1, &a2);
  return s;
}

// Projected (E, N) in EPSG `epsg` of a WGS84 point, by OSR directly.
inline Eigen::Vector2d OsrProject(const Eigen::Vector2d& lon_lat, int epsg) {
  OGRSpatialReference wgs, proj;
  wgs.importFromEPSG(4326);
  proj.importFromEPSG(epsg);
  wgs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  proj.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> t(OGRCreateCoordinateTransformation(&wgs, &proj));
  double x = lon_lat.x(), y = lon_lat.y();
  EXPECT_TRUE(t && t->Transform(1, &x, &y));
  return {x, y};
}

inline Eigen::Vector2d ExpectedProjected(const GeoAnchorOptions& a, const Eigen::Vector2d& p,
                                         int epsg) {
  return OsrProject(GeodesicLonLat(a, p), epsg);
}

// A fresh, empty folder under the system temp dir, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("plantscale_maps_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
             std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace plantscale::maps::testing
