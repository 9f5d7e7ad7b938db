#include "engine/geometry/centroid_height.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace plantscale::geometry {

OptionErrors CropShape::Validate() const {
  OptionErrors e;
  RequirePositive(e, "radius_m", radius_m);
  RequirePositive(e, "height_m", height_m);
  return e;
}

OptionErrors CentroidHeightOptions::Validate() const {
  OptionErrors e = Prefixed("shape", shape.Validate());
  RequirePositive(e, "node_spacing_px", node_spacing_px);
  if (samples < 4 || samples > 1000) e.push_back({"samples", "must be in [4, 1000]"});
  return e;
}

bool RayHitsCrop(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector2d& root,
                 const CropShape& shape) {
  if (d.z() >= 0.0) return false;
  // The ray's horizontal position at height z, relative to the root:
  // q(z) = a + z·w with w = d_xy / d_z. Inside the solid where
  // f(z) = R²(2z/h − z²/h²) − |q(z)|² ≥ 0, a concave quadratic in z: test
  // its maximum over [0, h].
  const double r2 = shape.radius_m * shape.radius_m;
  const double h = shape.height_m;
  const Eigen::Vector2d w = d.head<2>() / d.z();
  const Eigen::Vector2d a = o.head<2>() - root - o.z() * w;
  const double curvature = r2 / (h * h) + w.squaredNorm();
  const double z = std::clamp((r2 / h - a.dot(w)) / curvature, 0.0, h);
  const Eigen::Vector2d q = a + z * w;
  return r2 * (2.0 * z / h - z * z / (h * h)) - q.squaredNorm() >= 0.0;
}

namespace {

struct Box {
  Eigen::Vector2d low{INFINITY, INFINITY};
  Eigen::Vector2d high{-INFINITY, -INFINITY};
  void Add(const Eigen::Vector2d& p) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
};

// Image bounding box of the solid: it lies inside the cylinder of radius R
// from the soil to the rim (the bowl bulges outside the cone from the root
// to the rim).
std::optional<Box> SilhouetteBox(const CameraModel& camera, const Eigen::Vector2d& root,
                                 const CropShape& shape) {
  constexpr int kRimPoints = 48;
  Box box;
  for (const double z : {0.0, shape.height_m}) {
    for (int i = 0; i < kRimPoints; ++i) {
      const double a = 2.0 * std::numbers::pi * i / kRimPoints;
      const auto p = camera.Project(
          {root.x() + shape.radius_m * std::cos(a), root.y() + shape.radius_m * std::sin(a), z});
      if (!p) return std::nullopt;
      box.Add(*p);
    }
  }
  // A chord of the 48-gon lies inside the circle by R(1 − cos(π/48)) ≈ 0.2 %.
  const Eigen::Vector2d pad = 0.01 * (box.high - box.low) + Eigen::Vector2d::Constant(0.5);
  box.low -= pad;
  box.high += pad;
  return box;
}

}  // namespace

std::optional<double> SilhouetteCentroidHeight(const CameraModel& camera,
                                               const Eigen::Vector2d& root, const CropShape& shape,
                                               int samples) {
  const std::optional<Box> box = SilhouetteBox(camera, root, shape);
  if (!box) return std::nullopt;
  const Eigen::Vector3d o = camera.centre();
  const Eigen::Vector2d step = (box->high - box->low) / samples;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int hits = 0;
  for (int j = 0; j < samples; ++j) {
    for (int i = 0; i < samples; ++i) {
      const Eigen::Vector2d uv =
          box->low + Eigen::Vector2d((i + 0.5) * step.x(), (j + 0.5) * step.y());
      if (!RayHitsCrop(o, camera.Ray(uv), root, shape)) continue;
      sum += uv;
      ++hits;
    }
  }
  if (hits == 0) return std::nullopt;
  // Where the centroid's ray passes closest to the plant's vertical axis.
  const Eigen::Vector3d r = camera.Ray(sum / hits);
  const double horizontal2 = r.head<2>().squaredNorm();
  if (horizontal2 < 1e-18) return shape.height_m;  // straight down the axis: the rim's disc
  const double t = (root - o.head<2>()).dot(r.head<2>()) / horizontal2;
  return o.z() + t * r.z();
}

CentroidHeights::CentroidHeights(const CameraModel& camera, const CentroidHeightOptions& options)
    : camera_(camera), options_(options) {
  ThrowIfInvalid("centroid heights", options.Validate());
  const double s = options.node_spacing_px;
  columns_ = static_cast<int>(std::ceil(camera.width() / s)) + 1;
  rows_ = static_cast<int>(std::ceil(camera.height() / s)) + 1;
  heights_.assign(static_cast<size_t>(columns_ * rows_), NAN);
  // Bottom row first, so that a node whose plant cannot be placed (beyond
  // the horizon) takes the height of the node below it.
  for (int j = rows_ - 1; j >= 0; --j) {
    for (int i = 0; i < columns_; ++i) {
      const Eigen::Vector2d uv(std::min(i * s, 1.0 * camera.width()),
                               std::min(j * s, 1.0 * camera.height()));
      double h = NodeHeight(uv);
      if (!std::isfinite(h)) {
        h = j + 1 < rows_ ? heights_[static_cast<size_t>((j + 1) * columns_ + i)]
                          : camera.options().virtual_plane_height_m;
      }
      heights_[static_cast<size_t>(j * columns_ + i)] = h;
    }
  }
}

double CentroidHeights::NodeHeight(const Eigen::Vector2d& uv) const {
  // The plant whose centroid appears at uv stands where uv's ray meets the
  // centroid height, which depends on where it stands: two fixed-point
  // steps from three quarters of the plant's height (the change of the
  // height over the step is a few millimetres, its effect on the next
  // height a tenth of that).
  double h = 0.75 * options_.shape.height_m;
  for (int k = 0; k < 3; ++k) {
    const auto root = camera_.ImageToPlane(uv, h);
    if (!root) return NAN;
    const auto next = SilhouetteCentroidHeight(camera_, *root, options_.shape, options_.samples);
    if (!next) return NAN;
    h = *next;
  }
  return h;
}

double CentroidHeights::HeightAt(const Eigen::Vector2d& uv) const {
  const double s = options_.node_spacing_px;
  const double fu = std::clamp(uv.x() / s, 0.0, columns_ - 1.0);
  const double fv = std::clamp(uv.y() / s, 0.0, rows_ - 1.0);
  const int i = std::min(static_cast<int>(fu), columns_ - 2);
  const int j = std::min(static_cast<int>(fv), rows_ - 2);
  const double a = fu - i;
  const double b = fv - j;
  auto at = [&](int ii, int jj) { return heights_[static_cast<size_t>(jj * columns_ + ii)]; };
  return (1 - b) * ((1 - a) * at(i, j) + a * at(i + 1, j)) +
         b * ((1 - a) * at(i, j + 1) + a * at(i + 1, j + 1));
}

std::optional<Eigen::Vector2d> CentroidHeights::Locate(const Eigen::Vector2d& uv) const {
  return camera_.ImageToPlane(uv, HeightAt(uv));
}

Eigen::Matrix2d CentroidHeights::LocateJacobian(const Eigen::Vector2d& uv) const {
  return camera_.ImageToPlaneJacobian(uv, HeightAt(uv));
}

}  // namespace plantscale::geometry
