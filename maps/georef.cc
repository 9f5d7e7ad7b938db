#include "maps/georef.h"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "maps/gdal_util.h"

namespace plantscale::maps {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

using TransformPtr =
    std::unique_ptr<OGRCoordinateTransformation, decltype(&OGRCoordinateTransformation::DestroyCT)>;

OGRSpatialReference Wgs84() {
  OGRSpatialReference srs;
  srs.SetWellKnownGeogCS("WGS84");
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // (lon, lat)
  return srs;
}

OGRSpatialReference LocalTmerc(const GeoAnchorOptions& o) {
  std::ostringstream proj;
  proj.precision(17);
  proj << "+proj=tmerc +lat_0=" << o.latitude_deg << " +lon_0=" << o.longitude_deg
       << " +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m +no_defs";
  OGRSpatialReference srs;
  if (srs.importFromProj4(proj.str().c_str()) != OGRERR_NONE) {
    throw InvalidOptionsError("georeference", {{"origin", "cannot build " + proj.str()}});
  }
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

OGRSpatialReference Projected(int epsg) {
  GdalErrorScope errors;
  OGRSpatialReference srs;
  if (srs.importFromEPSG(epsg) != OGRERR_NONE) {
    throw InvalidOptionsError(
        "georeference", {{"epsg", "unknown EPSG code " + std::to_string(epsg) + errors.Suffix()}});
  }
  if (!srs.IsProjected()) {
    throw InvalidOptionsError("georeference",
                              {{"epsg", "EPSG:" + std::to_string(epsg) + " (" + srs.GetName() +
                                            ") is not a projected CRS in metres"}});
  }
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // (easting, northing)
  return srs;
}

TransformPtr MakeTransform(const OGRSpatialReference& from, const OGRSpatialReference& to) {
  GdalErrorScope errors;
  TransformPtr t(OGRCreateCoordinateTransformation(&from, &to),
                 &OGRCoordinateTransformation::DestroyCT);
  if (!t) {
    throw InvalidOptionsError("georeference",
                              {{"epsg", "no transformation to the export CRS" + errors.Suffix()}});
  }
  return t;
}

Eigen::Vector2d Apply(OGRCoordinateTransformation& t, const Eigen::Vector2d& p) {
  double x = p.x();
  double y = p.y();
  if (!t.Transform(1, &x, &y)) {
    std::ostringstream where;
    where << "point (" << p.x() << ", " << p.y() << ") cannot be transformed";
    throw DataError(where.str());
  }
  return {x, y};
}

}  // namespace

OptionErrors GeoAnchorOptions::Validate() const {
  OptionErrors errors;
  RequireInRange(errors, "latitude_deg", latitude_deg, -90.0, 90.0);
  RequireInRange(errors, "longitude_deg", longitude_deg, -180.0, 180.0);
  RequireInRange(errors, "heading_deg", heading_deg, -360.0, 360.0);
  if (epsg == 0 && std::isfinite(latitude_deg) && std::abs(latitude_deg) <= 90.0 &&
      !(latitude_deg >= -80.0 && latitude_deg <= 84.0)) {
    errors.push_back({"latitude_deg", "UTM covers latitudes -80..84 only; give an EPSG code"});
  }
  if (epsg < 0) errors.push_back({"epsg", "must be a positive EPSG code or 0 for UTM"});
  return errors;
}

int UtmEpsg(double latitude_deg, double longitude_deg) {
  int zone = static_cast<int>(std::floor((longitude_deg + 180.0) / 6.0)) + 1;
  zone = std::clamp(zone, 1, 60);
  const double lat = latitude_deg;
  const double lon = longitude_deg;
  if (lat >= 56.0 && lat < 64.0 && lon >= 3.0 && lon < 12.0) zone = 32;  // south-west Norway
  if (lat >= 72.0 && lat < 84.0 && lon >= 0.0 && lon < 42.0) {           // Svalbard
    zone = lon < 9.0 ? 31 : lon < 21.0 ? 33 : lon < 33.0 ? 35 : 37;
  }
  return (lat >= 0.0 ? 32600 : 32700) + zone;
}

struct Georeference::Impl {
  OGRSpatialReference wgs84;
  OGRSpatialReference local;
  OGRSpatialReference projected;
  TransformPtr local_to_projected{nullptr, &OGRCoordinateTransformation::DestroyCT};
  TransformPtr local_to_wgs84{nullptr, &OGRCoordinateTransformation::DestroyCT};
  TransformPtr wgs84_to_local{nullptr, &OGRCoordinateTransformation::DestroyCT};
};

Georeference::Georeference(const GeoAnchorOptions& options) : options_(options) {
  ThrowIfInvalid("georeference (--origin, --heading, --epsg)", options_.Validate());
  EnsureGdalRegistered();
  epsg_ =
      options_.epsg != 0 ? options_.epsg : UtmEpsg(options_.latitude_deg, options_.longitude_deg);
  impl_ = std::make_unique<Impl>();
  impl_->wgs84 = Wgs84();
  impl_->local = LocalTmerc(options_);
  impl_->projected = Projected(epsg_);
  impl_->local_to_projected = MakeTransform(impl_->local, impl_->projected);
  impl_->local_to_wgs84 = MakeTransform(impl_->local, impl_->wgs84);
  impl_->wgs84_to_local = MakeTransform(impl_->wgs84, impl_->local);
}

Georeference::~Georeference() = default;
Georeference::Georeference(Georeference&&) noexcept = default;
Georeference& Georeference::operator=(Georeference&&) noexcept = default;

std::string Georeference::ProjectedWkt() const {
  char* wkt = nullptr;
  impl_->projected.exportToWkt(&wkt);
  std::string text = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  return text;
}

std::string Georeference::ProjectedName() const {
  const char* name = impl_->projected.GetName();
  return name != nullptr ? name : "EPSG:" + std::to_string(epsg_);
}

Eigen::Vector2d Georeference::FieldToLocal(const Eigen::Vector2d& f) const {
  const double h = options_.heading_deg * kDegToRad;
  return {f.x() * std::cos(h) + f.y() * std::sin(h), -f.x() * std::sin(h) + f.y() * std::cos(h)};
}

Eigen::Vector2d Georeference::LocalToField(const Eigen::Vector2d& l) const {
  const double h = options_.heading_deg * kDegToRad;
  return {l.x() * std::cos(h) - l.y() * std::sin(h), l.x() * std::sin(h) + l.y() * std::cos(h)};
}

Eigen::Vector2d Georeference::FieldToProjected(const Eigen::Vector2d& field_m) const {
  return Apply(*impl_->local_to_projected, FieldToLocal(field_m));
}

Eigen::Vector2d Georeference::FieldToWgs84(const Eigen::Vector2d& field_m) const {
  return Apply(*impl_->local_to_wgs84, FieldToLocal(field_m));
}

Eigen::Vector2d Georeference::Wgs84ToField(const Eigen::Vector2d& lon_lat_deg) const {
  return LocalToField(Apply(*impl_->wgs84_to_local, lon_lat_deg));
}

std::vector<Eigen::Vector2d> Georeference::Wgs84ToField(
    const std::vector<Eigen::Vector2d>& lon_lat_deg) const {
  std::vector<double> x(lon_lat_deg.size());
  std::vector<double> y(lon_lat_deg.size());
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = lon_lat_deg[i].x();
    y[i] = lon_lat_deg[i].y();
  }
  if (!impl_->wgs84_to_local->Transform(x.size(), x.data(), y.data())) {
    throw DataError("WGS84 points cannot be transformed into the field frame");
  }
  std::vector<Eigen::Vector2d> out(x.size());
  for (size_t i = 0; i < x.size(); ++i) out[i] = LocalToField({x[i], y[i]});
  return out;
}

std::array<double, 6> Georeference::GeoTransform(const MapGrid& grid, double* max_error_m) const {
  // Raster pixel (P, L) ↔ field (x0 + P·res, y0 + (rows − L)·res).
  auto field_of = [&](double p, double l) {
    return Eigen::Vector2d(grid.origin_m().x() + p * grid.resolution_m(),
                           grid.origin_m().y() + (grid.rows() - l) * grid.resolution_m());
  };
  const Eigen::Vector2d p0 = FieldToProjected(field_of(0, 0));
  const Eigen::Vector2d dp = (FieldToProjected(field_of(grid.cols(), 0)) - p0) / grid.cols();
  const Eigen::Vector2d dl = (FieldToProjected(field_of(0, grid.rows())) - p0) / grid.rows();
  const std::array<double, 6> gt{p0.x(), dp.x(), dl.x(), p0.y(), dp.y(), dl.y()};
  if (max_error_m != nullptr) {
    *max_error_m = 0.0;
    const double c = grid.cols();
    const double r = grid.rows();
    for (auto [p, l] : {std::pair{c, r}, std::pair{c / 2, r / 2}, std::pair{c, 0.0}}) {
      const Eigen::Vector2d affine(gt[0] + p * gt[1] + l * gt[2], gt[3] + p * gt[4] + l * gt[5]);
      *max_error_m = std::max(*max_error_m, (affine - FieldToProjected(field_of(p, l))).norm());
    }
  }
  return gt;
}

}  // namespace plantscale::maps
