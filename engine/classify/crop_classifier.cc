#include "engine/classify/crop_classifier.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "engine/tracking/observation_model.h"

namespace plantscale::classify {

OptionErrors ClassifierOptions::Validate() const {
  OptionErrors e;
  RequireNonNegative(e, "min_crop_area_m2", min_crop_area_m2);
  RequirePositive(e, "assoc_chi2", assoc_chi2);
  if (!(sure_crop_area_m2 > 0.0)) e.push_back({"sure_crop_area_m2", "must be > 0 (inf: never)"});
  RequirePositive(e, "feature_sd_m", feature_sd_m);
  RequireNonNegative(e, "plant_sd_m", plant_sd_m);
  RequireNonNegative(e, "camera_pitch_sd_rad", camera_pitch_sd_rad);
  RequireNonNegative(e, "camera_roll_sd_rad", camera_roll_sd_rad);
  RequireNonNegative(e, "camera_height_sd_m", camera_height_sd_m);
  RequirePositive(e, "split_radius_m", split_radius_m);
  RequirePositive(e, "split_assoc_chi2", split_assoc_chi2);
  RequireNonNegative(e, "split_cover_m", split_cover_m);
  RequireNonNegative(e, "split_clipped_reach", split_clipped_reach);
  RequireNonNegative(e, "fragment_reach", fragment_reach);
  RequireInRange(e, "crop_size_fraction", crop_size_fraction, 0.0, 1.0);
  if (crop_size_window < 1) e.push_back({"crop_size_window", "must be >= 1"});
  if (crop_size_min_samples < 1 || crop_size_min_samples > crop_size_window) {
    e.push_back({"crop_size_min_samples", "must be in [1, crop_size_window]"});
  }
  RequireInRange(e, "lone_crop_fraction", lone_crop_fraction, 0.0, 1.0);
  RequireNonNegative(e, "outline_limit_sd", outline_limit_sd);
  RequireNonNegative(e, "learned_min_confidence", learned_min_confidence);
  return e;
}

std::vector<PredictedCrop> PredictCrops(const geometry::GridModel& model,
                                        const geometry::GridState& state, double reach_m) {
  std::vector<PredictedCrop> out;
  const auto& cam = model.camera().options();
  const double above_plane_m = cam.height_m - cam.virtual_plane_height_m;
  for (const geometry::GridPlant& g : model.PlantsReachingView(state, reach_m)) {
    PredictedCrop c;
    c.m = g.m;
    c.n = g.n;
    c.ground_m = geometry::PlantInVehicle(state, g.m, g.n);
    c.jacobian = geometry::PlantInVehicleJacobian(state, g.m, g.n);
    c.bounce_jacobian = tracking::BounceJacobian(c.ground_m, above_plane_m);
    out.push_back(c);
  }
  return out;
}

Eigen::Matrix2d AssociationCovariance(const PredictedCrop& crop, const geometry::Matrix5d& p,
                                      const ClassifierOptions& o) {
  // Eq. 7.4: S_assoc = H P Hᵀ + F_w R F_wᵀ; R on the ground is isotropic.
  const double r = o.feature_sd_m * o.feature_sd_m + o.plant_sd_m * o.plant_sd_m;
  const Eigen::Vector3d bounce(o.camera_pitch_sd_rad, o.camera_roll_sd_rad, o.camera_height_sd_m);
  const Eigen::Matrix3d b = bounce.cwiseAbs2().asDiagonal();
  return crop.jacobian * p * crop.jacobian.transpose() +
         crop.bounce_jacobian * b * crop.bounce_jacobian.transpose() +
         r * Eigen::Matrix2d::Identity();
}

void FuseLearned(int learned_class, double confidence, const ClassifierOptions& options,
                 BlobDecision& d) {
  d.learned_class = learned_class;
  d.learned_confidence = confidence;
  d.learned = false;
  if (!(confidence >= options.learned_min_confidence)) return;
  if (learned_class == 1) {
    d.crop = true;
    d.learned = true;
  } else if (learned_class == 2) {
    d.crop = false;
    d.associated = false;
    d.fragment = false;
    d.lone = false;
    d.learned = true;
  }
}

bool IsCrop(double area_m2, bool clipped, double gamma2, double min_crop_area_m2,
            double assoc_chi2, double sure_crop_area_m2) {
  if (!clipped && area_m2 < min_crop_area_m2) return false;  // size filter first
  if (area_m2 >= sure_crop_area_m2) return true;             // merged plants
  return gamma2 <= assoc_chi2;
}

CropClassifier::CropClassifier(const ClassifierOptions& options) : options_(options) {
  ThrowIfInvalid("crop classifier", options_.Validate());
  size_filter_m2_ = options_.min_crop_area_m2;
}

void CropClassifier::RememberCropArea(double area_m2) {
  if (!(options_.crop_size_fraction > 0.0) || !std::isfinite(area_m2)) return;
  if (crop_areas_.size() < static_cast<size_t>(options_.crop_size_window)) {
    crop_areas_.push_back(area_m2);
  } else {
    crop_areas_[next_area_] = area_m2;
    next_area_ = (next_area_ + 1) % crop_areas_.size();
  }
}

double CropClassifier::typical_crop_radius_m() const {
  return std::sqrt(median_crop_area_m2_ / M_PI);
}

double CropClassifier::crop_reach_m() const {
  return options_.split_clipped_reach * typical_crop_radius_m();
}

void CropClassifier::UpdateSizeFilter() {
  if (crop_areas_.size() < static_cast<size_t>(options_.crop_size_min_samples)) return;
  scratch_.assign(crop_areas_.begin(), crop_areas_.end());
  const auto mid = scratch_.begin() + static_cast<std::ptrdiff_t>(scratch_.size() / 2);
  std::nth_element(scratch_.begin(), mid, scratch_.end());
  median_crop_area_m2_ = *mid;
  size_filter_m2_ = std::min(options_.min_crop_area_m2, options_.crop_size_fraction * *mid);
}

void CropClassifier::Classify(std::span<const tracking::Feature> features,
                              std::span<const PredictedCrop> predictions,
                              const geometry::Matrix5d& covariance,
                              std::vector<BlobDecision>& out) {
  std::vector<Eigen::Matrix2d> s_inverse;
  s_inverse.reserve(predictions.size());
  for (const PredictedCrop& c : predictions) {
    s_inverse.push_back(AssociationCovariance(c, covariance, options_).inverse());
  }
  out.clear();
  for (const tracking::Feature& f : features) out.push_back(Decide(f, predictions, s_inverse));
  MarkFragments(features, out);
  MarkLoneCrops(out);
  // Learnt after the frame, so every blob of a frame meets the same filter.
  for (const BlobDecision& d : out) {
    if (d.crop && d.associated && !d.clipped && !d.lone) RememberCropArea(d.area_m2);
  }
  UpdateSizeFilter();
}

// The thesis's rule on one blob: its nearest prediction by γ², then crop
// when associated and above the size filter (IsCrop).
BlobDecision CropClassifier::Decide(const tracking::Feature& f, std::span<const PredictedCrop> predictions,
                                    std::span<const Eigen::Matrix2d> s_inverse) const {
  BlobDecision d;
  d.area_m2 = f.area_m2;
  d.clipped = f.clipped;
  for (size_t i = 0; i < predictions.size(); ++i) {
    const Eigen::Vector2d nu = f.ground_m - predictions[i].ground_m;
    const double g2 = nu.dot(s_inverse[i] * nu);
    if (g2 < d.gamma2) {
      d.gamma2 = g2;
      d.distance_m = nu.norm();
      d.m = predictions[i].m;
      d.n = predictions[i].n;
      d.predicted_ground_m = predictions[i].ground_m;
    }
  }
  d.associated = d.gamma2 <= options_.assoc_chi2;
  d.size_filter_m2 = size_filter_m2_;
  d.crop = !predictions.empty() &&
           IsCrop(d.area_m2, d.clipped, d.gamma2, size_filter_m2_, options_.assoc_chi2,
                  options_.sure_crop_area_m2);
  return d;
}

// Leaf fragments of the crops found (ClassifierOptions::fragment_reach).
void CropClassifier::MarkFragments(std::span<const tracking::Feature> features,
                                   std::vector<BlobDecision>& out) const {
  const double reach = options_.fragment_reach * typical_crop_radius_m();
  if (!(reach > 0.0)) return;
  for (size_t i = 0; i < out.size(); ++i) {
    BlobDecision& d = out[i];
    if (d.crop || d.clipped || !(d.area_m2 < d.size_filter_m2)) continue;
    for (size_t j = 0; j < out.size() && !d.crop; ++j) {
      const BlobDecision& c = out[j];
      if (!c.crop || !c.associated || c.fragment) continue;
      if ((features[i].ground_m - c.predicted_ground_m).norm() <= reach) {
        d.crop = d.fragment = true;
        d.m = c.m;
        d.n = c.n;
      }
    }
  }
}

// Lone small crops (ClassifierOptions::lone_crop_fraction).
void CropClassifier::MarkLoneCrops(std::vector<BlobDecision>& out) const {
  if (!(options_.lone_crop_fraction > 0.0)) return;
  for (BlobDecision& d : out) {
    if (d.crop || d.clipped || !d.associated ||
        d.area_m2 < options_.lone_crop_fraction * d.size_filter_m2) {
      continue;
    }
    const bool taken = std::any_of(out.begin(), out.end(), [&](const BlobDecision& c) {
      return c.crop && c.associated && c.m == d.m && c.n == d.n;
    });
    if (!taken) d.crop = d.lone = true;
  }
}

int CropClassifier::SplitMerged(std::span<const Eigen::Vector2d> ground_m,
                                std::span<const double> pixel_area_m2, bool clipped,
                                std::span<const PredictedCrop> predictions,
                                const geometry::Matrix5d& covariance, std::vector<uint8_t>& crop,
                                std::vector<int>* part_out) const {
  if (pixel_area_m2.size() != ground_m.size()) {
    throw std::invalid_argument("SplitMerged: " + std::to_string(ground_m.size()) +
                                " ground points but " + std::to_string(pixel_area_m2.size()) +
                                " pixel areas");
  }
  crop.assign(ground_m.size(), 0);
  std::vector<int> local;
  std::vector<int>& part = part_out ? *part_out : local;
  part.assign(ground_m.size(), -1);
  if (predictions.empty() || ground_m.empty()) return 0;
  // Parts: nearest prediction per pixel (−1: none within the radius).
  const double r2 = options_.split_radius_m * options_.split_radius_m;
  std::vector<double> area(predictions.size(), 0.0);
  std::vector<Eigen::Vector2d> moment(predictions.size(), Eigen::Vector2d::Zero());
  std::vector<double> nearest2(predictions.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < ground_m.size(); ++i) {
    double best = r2;
    for (size_t k = 0; k < predictions.size(); ++k) {
      const double d2 = (ground_m[i] - predictions[k].ground_m).squaredNorm();
      if (d2 <= best) {
        best = d2;
        part[i] = static_cast<int>(k);
      }
    }
    if (part[i] < 0) continue;
    const auto k = static_cast<size_t>(part[i]);
    area[k] += pixel_area_m2[i];
    moment[k] += pixel_area_m2[i] * ground_m[i];
    nearest2[k] = std::min(nearest2[k], best);
  }
  // Plant matter this close to a prediction covers it.
  const double cover_m =
      clipped ? std::max(options_.split_cover_m, crop_reach_m()) : options_.split_cover_m;
  std::vector<uint8_t> part_crop(predictions.size(), 0);
  int parts = 0;
  for (size_t k = 0; k < predictions.size(); ++k) {
    if (!(area[k] > 0.0)) continue;
    // A part with plant matter on its prediction is inside its region
    // (γ² = 0) whatever its cut centroid; the size filter still applies.
    const bool covers = nearest2[k] <= cover_m * cover_m;
    const Eigen::Vector2d nu = moment[k] / area[k] - predictions[k].ground_m;
    const Eigen::Matrix2d s = AssociationCovariance(predictions[k], covariance, options_);
    const double g2 = covers ? 0.0 : nu.dot(s.ldlt().solve(nu));
    part_crop[k] = IsCrop(area[k], clipped, g2, size_filter_m2_, options_.split_assoc_chi2,
                          options_.sure_crop_area_m2);
    parts += part_crop[k];
  }
  for (size_t i = 0; i < ground_m.size(); ++i) {
    if (part[i] >= 0) crop[i] = part_crop[static_cast<size_t>(part[i])];
  }
  return parts;
}

namespace {

// Flags the points beyond `limit_sd` of the ellipse of the points not yet
// flagged. False when that ellipse is degenerate.
bool FlagBeyondEllipse(std::span<const Eigen::Vector2d> p, double limit_sd, std::vector<uint8_t>& beyond) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
  double n = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (beyond[i]) continue;
    sum += p[i];
    outer += p[i] * p[i].transpose();
    n += 1.0;
  }
  if (n < 8.0) return false;
  const Eigen::Vector2d mean = sum / n;
  const Eigen::Matrix2d cov = outer / n - mean * mean.transpose();
  if (!(cov.determinant() > 1e-18) || !(cov.trace() > 0.0)) return false;
  const Eigen::Matrix2d inv = cov.inverse();
  const double limit2 = limit_sd * limit_sd;
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d d = p[i] - mean;
    beyond[i] = d.dot(inv * d) > limit2 ? 1 : 0;
  }
  return true;
}

}  // namespace

int BeyondCropOutline(std::span<const Eigen::Vector2d> ground_m, double limit_sd,
                      std::vector<uint8_t>& beyond) {
  beyond.assign(ground_m.size(), 0);
  if (!(limit_sd > 0.0) || ground_m.size() < 8) return 0;
  for (int pass = 0; pass < 2; ++pass) {
    if (!FlagBeyondEllipse(ground_m, limit_sd, beyond)) {
      beyond.assign(ground_m.size(), 0);
      return 0;
    }
  }
  return static_cast<int>(std::count(beyond.begin(), beyond.end(), uint8_t{1}));
}

}  // namespace plantscale::classify
