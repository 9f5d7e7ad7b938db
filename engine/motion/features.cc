#include "engine/motion/features.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "engine/motion/virtual_plane.h"

namespace plantscale::motion {
namespace {

// Index reached walking from i along the closed contour (step ±1) until the
// arc length covered is at least arm_m; stops after one lap.
int ArmIndex(std::span<const Eigen::Vector2d> c, int i, double arm_m, int step) {
  const int n = static_cast<int>(c.size());
  double covered = 0.0;
  int j = i;
  for (int k = 0; k < n - 1 && covered < arm_m; ++k) {
    const int next = (j + step + n) % n;
    covered += (c[next] - c[j]).norm();
    j = next;
  }
  return j;
}

bool ArmTouchesCut(std::span<const uint8_t> cut, int from, int to) {
  const int n = static_cast<int>(cut.size());
  for (int j = from;; j = (j + 1) % n) {
    if (cut[j] != 0) return true;
    if (j == to) return false;
  }
}

double SignedArea(std::span<const Eigen::Vector2d> c) {
  double area = 0.0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector2d& a = c[i];
    const Eigen::Vector2d& b = c[(i + 1) % c.size()];
    area += a.x() * b.y() - a.y() * b.x();
  }
  return area / 2.0;
}

double Sharpness(std::span<const Eigen::Vector2d> c, int i, double arm_m) {
  const Eigen::Vector2d a = c[ArmIndex(c, i, arm_m, -1)] - c[i];
  const Eigen::Vector2d b = c[ArmIndex(c, i, arm_m, +1)] - c[i];
  const double angle = std::atan2(std::abs(a.x() * b.y() - a.y() * b.x()), a.dot(b));
  return M_PI - angle;
}

double ContourLength(std::span<const Eigen::Vector2d> c) {
  double length = 0.0;
  for (size_t i = 0; i < c.size(); ++i) length += (c[(i + 1) % c.size()] - c[i]).norm();
  return length;
}

}  // namespace

OptionErrors FeatureOptions::Validate() const {
  OptionErrors e;
  RequireNonNegative(e, "plane_height_m", plane_height_m);
  RequireNonNegative(e, "min_plant_area_m2", min_plant_area_m2);
  RequireNonNegative(e, "weed_plane_height_m", weed_plane_height_m);
  RequireNonNegative(e, "crop_height_per_radius", crop_height_per_radius);
  RequireNonNegative(e, "weed_height_per_radius", weed_height_per_radius);
  RequirePositive(e, "detection_arm_m", detection_arm_m);
  RequireInRange(e, "min_sharpness_rad", min_sharpness_rad, 0.0, M_PI, false, false);
  RequireInRange(e, "characteristic_arm_fraction", characteristic_arm_fraction, 0.0, 0.5, false);
  RequireNonNegative(e, "border_margin_px", border_margin_px);
  RequirePositive(e, "max_features_per_blob", max_features_per_blob);
  return e;
}

void ConvexityOrientation(const Eigen::Vector2d& a, const Eigen::Vector2d& p,
                          const Eigen::Vector2d& b, double convex_sign, double& alpha_rad,
                          double& beta_rad) {
  // Fig. 7: α between segments p→a and p→b, signed by the turn a→p→b;
  // β the bisector's angle from the horizontal axis.
  const Eigen::Vector2d da = (a - p).normalized(), db = (b - p).normalized();
  const double turn = (p - a).x() * (b - p).y() - (p - a).y() * (b - p).x();
  const double magnitude = std::acos(std::clamp(da.dot(db), -1.0, 1.0));
  alpha_rad = (turn * convex_sign >= 0.0 ? 1.0 : -1.0) * magnitude;
  Eigen::Vector2d bisector = da + db;
  if (bisector.squaredNorm() < 1e-12) bisector = Eigen::Vector2d(-da.y(), da.x());
  // The bisector points into the blob when convex; point it outwards.
  if (alpha_rad > 0.0) bisector = -bisector;
  beta_rad = std::atan2(bisector.y(), bisector.x());
}

std::vector<int> DominantPoints(std::span<const Eigen::Vector2d> contour_m,
                                std::span<const uint8_t> cut, const FeatureOptions& options) {
  const int n = static_cast<int>(contour_m.size());
  std::vector<int> points;
  if (n < 8) return points;
  std::vector<double> sharp(n);
  for (int i = 0; i < n; ++i) sharp[i] = Sharpness(contour_m, i, options.detection_arm_m);
  // Start scanning just after a point below the threshold so no segment wraps.
  int start = 0;
  while (start < n && sharp[start] > options.min_sharpness_rad) ++start;
  if (start == n) return points;
  std::vector<std::pair<double, int>> found;
  int best = -1;
  for (int k = 1; k <= n; ++k) {
    const int i = (start + k) % n;
    if (sharp[i] > options.min_sharpness_rad) {
      if (best < 0 || sharp[i] > sharp[best]) best = i;
      continue;
    }
    if (best < 0) continue;
    const int a = ArmIndex(contour_m, best, options.detection_arm_m, -1);
    const int b = ArmIndex(contour_m, best, options.detection_arm_m, +1);
    if (!ArmTouchesCut(cut, a, b)) found.emplace_back(sharp[best], best);
    best = -1;
  }
  std::sort(found.begin(), found.end(), std::greater<>());
  if (static_cast<int>(found.size()) > options.max_features_per_blob)
    found.resize(options.max_features_per_blob);
  for (const auto& f : found) points.push_back(f.second);
  return points;
}

double FeatureStability(int n_k, int detected, int not_in_view) {
  const int seen_before = n_k - not_in_view;
  return seen_before > 0 ? 100.0 * detected / seen_before : 0.0;  // eq. 5
}

FeatureExtractor::FeatureExtractor(const FeatureOptions& options) : options_(options) {
  ThrowIfInvalid("FeatureOptions", options.Validate());
}

bool FeatureExtractor::IsPlant(const vision::Blob& blob) const {
  return blob.on_ground && blob.ground_area_m2 >= options_.min_plant_area_m2;
}

double FeatureExtractor::PlaneHeight(const vision::Blob& blob, bool plant) const {
  const double ratio = plant ? options_.crop_height_per_radius : options_.weed_height_per_radius;
  if (ratio <= 0.0) return plant ? options_.plane_height_m : options_.weed_plane_height_m;
  return ratio * std::sqrt(blob.ground_area_m2 / M_PI);
}

const std::vector<Feature>& FeatureExtractor::Extract(std::span<const vision::Blob> blobs,
                                                      const geometry::CameraModel& camera) {
  features_.clear();
  for (size_t i = 0; i < blobs.size(); ++i) {
    const bool plant = IsPlant(blobs[i]);
    if ((plant || options_.weed_features) && blobs[i].on_ground && blobs[i].contour.size() >= 8)
      AddBlobFeatures(blobs[i], static_cast<int>(i), plant, camera);
  }
  return features_;
}

void FeatureExtractor::AddBlobFeatures(const vision::Blob& blob, int index, bool plant,
                                       const geometry::CameraModel& camera) {
  const int m = options_.border_margin_px;
  const double height = PlaneHeight(blob, plant);
  contour_m_.clear();
  cut_.clear();
  Eigen::Vector2d last(0.0, 0.0);
  for (const cv::Point& q : blob.contour) {
    const auto g = ImageToFeaturePlane(camera, {q.x + 0.5, q.y + 0.5}, height);
    const bool edge = q.x < m || q.y < m || q.x >= camera.width() - m || q.y >= camera.height() - m;
    if (g) last = *g;
    contour_m_.push_back(last);
    cut_.push_back(edge || !g ? 1 : 0);
  }
  const std::vector<int> dominant = DominantPoints(contour_m_, cut_, options_);
  if (dominant.empty()) return;
  const double arm = options_.characteristic_arm_fraction * ContourLength(contour_m_);
  const double convex_sign = SignedArea(contour_m_) >= 0.0 ? 1.0 : -1.0;
  for (int i : dominant) {
    Feature f;
    f.position_m = contour_m_[i];
    const int a = ArmIndex(contour_m_, i, arm, -1), b = ArmIndex(contour_m_, i, arm, +1);
    ConvexityOrientation(contour_m_[a], contour_m_[i], contour_m_[b], convex_sign, f.convexity_rad,
                         f.orientation_rad);
    f.pixel = {blob.contour[i].x + 0.5, blob.contour[i].y + 0.5};
    f.blob = index;
    f.on_plant = plant;
    features_.push_back(f);
  }
}

}  // namespace plantscale::motion
