#include "maps/georef.h"

#include <gtest/gtest.h>

#include <random>

#include "maps/test_maps.h"

namespace plantscale::maps {
namespace {

using testing::ExpectedProjected;
using testing::GeodesicDistanceM;
using testing::GeodesicLonLat;
using testing::TestAnchor;

TEST(Georeference, UtmZoneOfTheOrigin) {
  EXPECT_EQ(UtmEpsg(52.0, -0.4), 32630);   // England, zone 30N
  EXPECT_EQ(UtmEpsg(-33.9, 18.4), 32734);  // Cape Town, 34S
  EXPECT_EQ(UtmEpsg(60.0, 5.0), 32632);    // Bergen: the Norway exception
  EXPECT_EQ(UtmEpsg(78.0, 15.0), 32633);   // Svalbard
  EXPECT_EQ(UtmEpsg(10.0, 180.0), 32660);
  EXPECT_EQ(Georeference(TestAnchor()).epsg(), 32630);
}

TEST(Georeference, FieldLocalRoundTripIsExact) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  for (double heading : {0.0, 30.0, -135.0, 359.0}) {
    const Georeference g(TestAnchor(heading));
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector2d p(u(rng), u(rng));
      ASSERT_LT((g.LocalToField(g.FieldToLocal(p)) - p).norm(), 1e-9);  // 1 nm
      EXPECT_NEAR(g.FieldToLocal(p).norm(), p.norm(), 1e-9);            // a rotation
    }
  }
}

TEST(Georeference, FieldWgs84RoundTripWithinAMicrometre) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  const Georeference g(TestAnchor(30.0));
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    const Eigen::Vector2d p(u(rng), u(rng));
    worst = std::max(worst, (g.Wgs84ToField(g.FieldToWgs84(p)) - p).norm());
  }
  EXPECT_LT(worst, 1e-6);
  RecordProperty("worst_roundtrip_error_um", std::to_string(worst * 1e6));
}

TEST(Georeference, HeadingIsTheBearingOfFieldPlusYClockwiseFromTrueNorth) {
  for (double heading : {0.0, 30.0, 90.0, 200.0}) {
    const Georeference g(TestAnchor(heading));
    const Eigen::Vector2d o = g.FieldToWgs84({0, 0});
    const Eigen::Vector2d ahead = g.FieldToWgs84({0, 50});
    geod_geodesic geod;
    geod_init(&geod, 6378137.0, 1 / 298.257223563);
    double s = 0, azi1 = 0, azi2 = 0;
    geod_inverse(&geod, o.y(), o.x(), ahead.y(), ahead.x(), &s, &azi1, &azi2);
    EXPECT_NEAR(s, 50.0, 1e-6);  // metres are ground metres (1 µm)
    EXPECT_NEAR(std::remainder(azi1 - heading, 360.0), 0.0, 1e-7) << heading;  // degrees
    EXPECT_NEAR(o.x(), -0.4, 1e-12);
    EXPECT_NEAR(o.y(), 52.0, 1e-12);
  }
}

TEST(Georeference, FieldPointsLandWhereAnIndependentGeodesicPutsThem) {
  // Expectation: geodesic from the origin (PROJ geodesic.h), then OSR WGS84 →
  // UTM 30N; tolerance 1 mm.
  const GeoAnchorOptions a = TestAnchor(30.0);
  const Georeference g(a);
  double worst = 0.0;
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.45, 2.5),
                                   Eigen::Vector2d(-3, 40), Eigen::Vector2d(80, -60)}) {
    worst = std::max(worst, (g.FieldToProjected(p) - ExpectedProjected(a, p, 32630)).norm());
    EXPECT_LT(GeodesicDistanceM(g.FieldToWgs84(p), GeodesicLonLat(a, p)), 1e-3);
  }
  EXPECT_LT(worst, 1e-3);
  RecordProperty("worst_projected_error_um", std::to_string(worst * 1e6));
}

TEST(Georeference, AnyProjectedEpsg) {
  GeoAnchorOptions a = TestAnchor(10.0, 27700);  // British National Grid
  const Georeference g(a);
  EXPECT_EQ(g.epsg(), 27700);
  const Eigen::Vector2d p(1.5, 7.0);
  EXPECT_LT((g.FieldToProjected(p) - ExpectedProjected(a, p, 27700)).norm(), 1e-3);
}

TEST(Georeference, GeoTransformIsAffineWithinAMicrometreOverAField) {
  const Georeference g(TestAnchor(30.0));
  const MapGrid grid({0.02, {-1.5, -1.0}, 150, 2100});  // 3 m × 42 m
  double error = 1.0;
  const std::array<double, 6> gt = g.GeoTransform(grid, &error);
  EXPECT_LT(error, 1e-6);
  // Pixel (0, rows) is the grid origin (raster line 0 = largest y).
  const Eigen::Vector2d origin = g.FieldToProjected(grid.origin_m());
  EXPECT_NEAR(gt[0] + grid.rows() * gt[2], origin.x(), 1e-6);
  EXPECT_NEAR(gt[3] + grid.rows() * gt[5], origin.y(), 1e-6);
  // Cell edge in UTM = 2 cm × point scale k = k0 / sqrt(1 − (cos φ sin Δλ)²)
  // (spherical transverse Mercator; the ellipsoid changes k by < 1e-5 here).
  const double b = std::cos(52.0 * std::numbers::pi / 180) * std::sin(2.6 * std::numbers::pi / 180);
  EXPECT_NEAR(std::hypot(gt[1], gt[4]), 0.02 * 0.9996 / std::sqrt(1 - b * b), 0.02 * 1e-5);
}

void ExpectInvalid(const GeoAnchorOptions& a, const std::string& key, const std::string& reason) {
  try {
    Georeference g(a);
    FAIL() << "expected InvalidOptionsError for " << key;
  } catch (const InvalidOptionsError& e) {
    ASSERT_FALSE(e.errors().empty());
    EXPECT_EQ(e.errors()[0].key, key);
    EXPECT_NE(e.errors()[0].reason.find(reason), std::string::npos) << e.errors()[0].reason;
  }
}

TEST(Georeference, BadAnchorsAreRefusedNamingTheKey) {
  ExpectInvalid(TestAnchor(0, 999999), "epsg", "unknown EPSG code 999999");
  ExpectInvalid(TestAnchor(0, 4326), "epsg", "not a projected CRS");
  GeoAnchorOptions a = TestAnchor();
  a.latitude_deg = 91.0;
  ExpectInvalid(a, "latitude_deg", "must be in [-90, 90]");
  a = TestAnchor();
  a.longitude_deg = -180.5;
  ExpectInvalid(a, "longitude_deg", "must be in [-180, 180]");
  a = TestAnchor();
  a.latitude_deg = 85.0;  // beyond UTM; fine with a polar CRS
  ExpectInvalid(a, "latitude_deg", "UTM covers latitudes -80..84");
  a.epsg = 3413;
  EXPECT_EQ(Georeference(a).epsg(), 3413);
  a = TestAnchor();
  a.heading_deg = std::nan("");
  ExpectInvalid(a, "heading_deg", "must be in");
}

}  // namespace
}  // namespace plantscale::maps
