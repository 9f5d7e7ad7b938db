#include "engine/motion/feature_tracker.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "engine/common/check.h"

namespace plantscale::motion {
namespace {

Characteristics Of(const Feature& f) { return {f.convexity_rad, f.orientation_rad}; }

Eigen::Matrix2d Isotropic(double sigma_m) { return sigma_m * sigma_m * Eigen::Matrix2d::Identity(); }

}  // namespace

const char* Name(MotionMethod method) { return method == MotionMethod::kPaper ? "paper" : "ours"; }

const char* Name(LockLoss loss) {
  switch (loss) {
    case LockLoss::kNone: return "none";
    case LockLoss::kFirstFrame: return "first frame";
    case LockLoss::kNoFeatures: return "no features";
    case LockLoss::kDuplicateFrame: return "duplicate frame";
    case LockLoss::kNoTracks: return "all features new";
    case LockLoss::kTooFewMatches: return "too few matches";
    case LockLoss::kMotionJump: return "motion jump";
  }
  return "?";
}

namespace {

// Length of the image's footprint on the feature plane along the forward
// axis, down the middle column.
double ViewAlong(const geometry::CameraModel& camera, const Eigen::Matrix3d& plane_to_image) {
  const Eigen::Matrix3d image_to_plane = plane_to_image.inverse();
  const double u = 0.5 * camera.width();
  const Eigen::Vector2d top = (image_to_plane * Eigen::Vector3d(u, 0.0, 1.0)).hnormalized();
  const Eigen::Vector2d bottom = (image_to_plane * Eigen::Vector3d(u, camera.height(), 1.0)).hnormalized();
  return std::max(1e-3, std::abs(top.y() - bottom.y()));
}

}  // namespace

OptionErrors TrackerOptions::Validate() const {
  OptionErrors e;
  RequireInRange(e, "depth_tolerance", depth_tolerance, 0.0, 1.0, false, false);
  RequireInRange(e, "direction_tolerance_rad", direction_tolerance_rad, 0.0, M_PI, false);
  RequireNonNegative(e, "search_margin_m", search_margin_m);
  RequirePositive(e, "hough.psi_range_rad", hough.psi_range_rad);
  RequirePositive(e, "hough.psi_steps", hough.psi_steps);
  RequirePositive(e, "hough.join_m", hough.join_m);
  if (hough.open_m < hough.join_m) e.push_back({"hough.open_m", "must be >= hough.join_m"});
  RequirePositive(e, "residual_gate_m", residual_gate_m);
  RequirePositive(e, "prior_gate_m", prior_gate_m);
  for (OptionError& r : Prefixed("row_heading", row_heading.Validate())) e.push_back(std::move(r));
  RequireNonNegative(e, "similarity_weight_m", similarity_weight_m);
  if (min_matches < 2) e.push_back({"min_matches", "must be >= 2"});
  RequirePositive(e, "max_motion_change_m", max_motion_change_m);
  RequirePositive(e, "max_rotation_change_rad", max_rotation_change_rad);
  RequireNonNegative(e, "max_misses", max_misses);
  RequirePositive(e, "max_similarity_distance", max_similarity_distance);
  RequireInRange(e, "min_matched_fraction", min_matched_fraction, 0.0, 1.0);
  RequirePositive(e, "rotation_prior_sigma_rad", rotation_prior_sigma_rad);
  RequireInRange(e, "heading_return_per_frame", heading_return_per_frame, 0.0, 1.0);
  RequireInRange(e, "translation_smoothing", translation_smoothing, 0.0, 1.0, false);
  RequirePositive(e, "track_sigma_m", track_sigma_m);
  RequirePositive(e, "process_sigma_m", process_sigma_m);
  RequirePositive(e, "measurement_sigma_m", measurement_sigma_m);
  return e;
}

FeatureTracker::FeatureTracker(const TrackerOptions& options, const geometry::CameraModel& camera,
                               double plane_height_m)
    : options_(options), camera_(camera),
      plane_to_image_(camera.PlaneToImageHomography(plane_height_m)),
      view_along_m_(ViewAlong(camera, plane_to_image_)), rows_(options.row_heading) {
  ThrowIfInvalid("TrackerOptions", options.Validate());
  const bool paper = options.method == MotionMethod::kPaper;
  p0_ = Isotropic(paper ? options.track_sigma_m : options.measurement_sigma_m);
  r1_ = Isotropic(paper ? options.track_sigma_m : options.process_sigma_m);
  r2_ = p0_;
  last_motion_ = options.initial_motion;
  smoothed_t_m_ = options.initial_motion.t_m;
}

void FeatureTracker::SetMotionPrior(const PlanarMotion& prior, double psi_sd_rad) {
  PLANTSCALE_CHECK(psi_sd_rad > 0.0, "the prior's rotation needs a positive σ");
  if (options_.method == MotionMethod::kPaper) return;
  frame_prior_ = prior;
  frame_prior_psi_sd_rad_ = psi_sd_rad;
}

double FeatureTracker::PriorPsi() const {
  if (options_.method == MotionMethod::kPaper) return last_motion_.psi_rad;
  if (frame_prior_) return frame_prior_->psi_rad;
  return options_.heading_return_per_frame * WrapAngle(result_.pose.heading_rad - row_heading_rad_);
}

void FeatureTracker::MapRows(std::span<const Feature> features, double driven_m) {
  if (options_.method != MotionMethod::kOurs || !options_.fit_row_heading) return;
  rows_.Drive(driven_m);
  if (features.empty()) return;
  // A plant stays in view for view_along_m_ / driven_m frames: each frame's
  // sighting weighs its share, so every plant counts about once.
  const double weight = first_mapped_ ? std::min(1.0, driven_m / view_along_m_) : 1.0;
  first_mapped_ = true;
  struct BlobSum {
    int blob;
    Eigen::Vector2d sum_m;
    int count;
  };
  std::vector<BlobSum> blobs;  // each crop blob's features: their mean is its position
  for (const Feature& f : features) {
    if (!f.on_plant) continue;
    auto it = std::find_if(blobs.begin(), blobs.end(), [&](const BlobSum& b) { return b.blob == f.blob; });
    if (it == blobs.end()) it = blobs.insert(blobs.end(), {f.blob, Eigen::Vector2d::Zero(), 0});
    it->sum_m += f.position_m;
    ++it->count;
  }
  for (const BlobSum& b : blobs) {
    rows_.Add(result_.pose.ToWorld(b.sum_m / static_cast<double>(b.count)), weight);
  }
  row_heading_rad_ = rows_.heading_rad();
  row_fit_ = rows_.fit();
}

PlanarMotion FeatureTracker::CoastingMotion() const {
  if (options_.method == MotionMethod::kPaper) return last_motion_;
  if (frame_prior_) return *frame_prior_;
  return {PriorPsi(), smoothed_t_m_};
}

bool FeatureTracker::InView(const Eigen::Vector2d& p_m) const {
  const Eigen::Vector3d uvw = plane_to_image_ * p_m.homogeneous();
  if (uvw.z() <= 0.0) return false;
  return camera_.InImage(uvw.hnormalized(), options_.view_margin_px);
}

bool FeatureTracker::IsDuplicate(std::span<const Feature> features) const {
  if (features.size() != last_positions_.size()) return false;
  for (size_t i = 0; i < features.size(); ++i) {
    if ((features[i].position_m - last_positions_[i]).norm() > 1e-9) return false;
  }
  return true;
}

const FrameMotion& FeatureTracker::Update(std::span<const Feature> features) {
  result_.track_of_feature.assign(features.size(), -1);
  result_.candidates = result_.coherent = result_.matched = 0;
  result_.residual_rms_m = 0.0;
  if (first_) {
    first_ = false;
    Coast(features, LockLoss::kFirstFrame, true);
    result_.motion = PlanarMotion{};
    result_.pose = VehiclePose2{};
    MapRows(features, 0.0);
  } else if (features.empty()) {
    Coast(features, LockLoss::kNoFeatures, false);
  } else if (IsDuplicate(features)) {
    Coast(features, LockLoss::kDuplicateFrame, false);
  } else {
    std::vector<int> visible;
    for (size_t j = 0; j < tracks_.size(); ++j) {
      if (InView(CoastingMotion().Apply(tracks_[j].filter.position_m())))
        visible.push_back(static_cast<int>(j));
    }
    if (visible.empty()) {
      Coast(features, LockLoss::kNoTracks, true);
    } else {
      Advance(features, visible, Correspond(features, visible));
    }
  }
  last_positions_.clear();
  for (const Feature& f : features) last_positions_.push_back(f.position_m);
  frame_prior_.reset();
  return result_;
}

std::vector<Match> FeatureTracker::Correspond(std::span<const Feature> features,
                                              const std::vector<int>& visible) {
  // Step 1: similarity inside the epipolar search regions, two-way matches.
  const bool paper = options_.method == MotionMethod::kPaper;
  Eigen::MatrixXd dm = Eigen::MatrixXd::Constant(features.size(), visible.size(), kNoMatch);
  for (size_t i = 0; i < features.size(); ++i) {
    const SearchRegion region = EpipolarSearchRegion(
        features[i].position_m, CoastingMotion(), options_.depth_tolerance,
        options_.search_margin_m);
    for (size_t v = 0; v < visible.size(); ++v) {
      const Track& t = tracks_[visible[v]];
      if (!region.Contains(t.filter.position_m())) continue;
      const double d = SimilarityDistance(Of(features[i]), t.characteristics);
      if (paper) {
        dm(i, v) = d;
      } else if (d <= options_.max_similarity_distance) {
        dm(i, v) = frame_prior_ ? PriorCost(features[i], t, d) : d;
      }
    }
  }
  const std::vector<Match> candidates = TwoWayMatches(dm);
  result_.candidates = static_cast<int>(candidates.size());
  if (candidates.size() < 2) return {};
  // Step 2: rigidity by clustering in (ψ, t_x, t_y).
  std::vector<Eigen::Vector2d> prev, cur;
  for (const Match& m : candidates) {
    prev.push_back(tracks_[visible[m.second]].filter.position_m());
    cur.push_back(features[m.first].position_m);
  }
  const HoughResult hough = HoughSelect(prev, cur, PriorPsi(), options_.hough);
  std::vector<Match> matches;
  for (int c : hough.coherent) matches.push_back(candidates[c]);
  result_.coherent = static_cast<int>(matches.size());
  if (matches.size() < 2) return matches;
  // Steps 3–4: least squares, then the filter.
  PlanarMotion motion = Fit(features, visible, matches);
  if (options_.method == MotionMethod::kPaper) {
    std::erase_if(matches, [&](const Match& m) {
      return !ConsistentWithMotion(motion, tracks_[visible[m.second]].filter.position_m(),
                                   features[m.first].position_m, options_.depth_tolerance,
                                   options_.direction_tolerance_rad);
    });
  } else {
    matches = KeepWithinGate(features, visible, std::move(matches), motion);
  }
  if (matches.size() < 2) return matches;
  motion = Fit(features, visible, matches);
  // Step 5: the rest of the matching.
  return FinalMatches(features, visible, std::move(matches), motion);
}

double FeatureTracker::PriorCost(const Feature& f, const Track& t, double similarity) const {
  const double r = (f.position_m - frame_prior_->Apply(t.filter.position_m())).norm();
  return r <= options_.prior_gate_m ? r + options_.similarity_weight_m * similarity : kNoMatch;
}

std::vector<Match> FeatureTracker::KeepWithinGate(std::span<const Feature> features,
                                                  const std::vector<int>& visible,
                                                  std::vector<Match> matches,
                                                  const PlanarMotion& motion) const {
  std::erase_if(matches, [&](const Match& m) {
    const Eigen::Vector2d predicted = motion.Apply(tracks_[visible[m.second]].filter.position_m());
    return (features[m.first].position_m - predicted).norm() > options_.residual_gate_m;
  });
  return matches;
}

std::vector<Match> FeatureTracker::FinalMatches(std::span<const Feature> features,
                                                const std::vector<int>& visible,
                                                std::vector<Match> matches,
                                                const PlanarMotion& motion) const {
  std::vector<uint8_t> row_used(features.size(), 0), col_used(visible.size(), 0);
  for (const Match& m : matches) row_used[m.first] = col_used[m.second] = 1;
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(features.size(), visible.size(), kNoMatch);
  const bool paper = options_.method == MotionMethod::kPaper;
  for (size_t i = 0; i < features.size(); ++i) {
    for (size_t v = 0; v < visible.size(); ++v) {
      if (row_used[i] || col_used[v]) continue;
      const Track& t = tracks_[visible[v]];
      const Eigen::Vector2d& q = t.filter.position_m();
      const Eigen::Vector2d& p = features[i].position_m;
      const double d = SimilarityDistance(Of(features[i]), t.characteristics);
      if (paper) {
        if (ConsistentWithMotion(motion, q, p, options_.depth_tolerance,
                                 options_.direction_tolerance_rad))
          cost(i, v) = d;
      } else {
        const double r = (p - motion.Apply(q)).norm();
        if (r <= options_.residual_gate_m && d <= options_.max_similarity_distance)
          cost(i, v) = r + options_.similarity_weight_m * d;
      }
    }
  }
  for (const Match& m : GreedyMatches(cost, row_used, col_used)) matches.push_back(m);
  return matches;
}

PlanarMotion FeatureTracker::Fit(std::span<const Feature> features, const std::vector<int>& visible,
                                 const std::vector<Match>& matches) const {
  std::vector<Eigen::Vector2d> prev, cur;
  for (const Match& m : matches) {
    prev.push_back(tracks_[visible[m.second]].filter.position_m());
    cur.push_back(features[m.first].position_m);
  }
  PlanarMotion fit = FitRigidMotion(prev, cur);
  if (options_.method == MotionMethod::kPaper) return fit;
  // Ours: the row-following prior on ψ. Near the optimum the data cost is
  // S (ψ − ψ_fit)² / σ_m² with S = Σ|p − p̄|², so the posterior ψ is the
  // precision-weighted mean of ψ_fit and ψ_prior.
  Eigen::Vector2d mean_prev = Eigen::Vector2d::Zero(), mean_cur = Eigen::Vector2d::Zero();
  for (size_t k = 0; k < prev.size(); ++k) mean_prev += prev[k], mean_cur += cur[k];
  mean_prev /= static_cast<double>(prev.size());
  mean_cur /= static_cast<double>(cur.size());
  double s = 0.0;
  for (const Eigen::Vector2d& p : prev) s += (p - mean_prev).squaredNorm();
  const double data = s / (options_.measurement_sigma_m * options_.measurement_sigma_m);
  const double sigma_psi = frame_prior_ ? frame_prior_psi_sd_rad_ : options_.rotation_prior_sigma_rad;
  const double prior = 1.0 / (sigma_psi * sigma_psi);
  const double psi0 = PriorPsi();
  fit.psi_rad = psi0 + data * WrapAngle(fit.psi_rad - psi0) / (data + prior);
  fit.t_m = mean_cur - fit.R() * mean_prev;
  return fit;
}

bool FeatureTracker::SmoothContinuation(const PlanarMotion& motion) const {
  const PlanarMotion expected = CoastingMotion();
  return (motion.t_m - expected.t_m).norm() <= options_.max_motion_change_m &&
         std::abs(WrapAngle(motion.psi_rad - expected.psi_rad)) <=
             options_.max_rotation_change_rad;
}

void FeatureTracker::Advance(std::span<const Feature> features, const std::vector<int>& visible,
                             const std::vector<Match>& found) {
  std::vector<Match> matches = found;
  const bool paper = options_.method == MotionMethod::kPaper;
  const double needed =
      paper ? 0.0
            : options_.min_matched_fraction *
                  static_cast<double>(std::min(features.size(), visible.size()));
  if (static_cast<int>(matches.size()) < options_.min_matches ||
      static_cast<double>(matches.size()) < needed) {
    Coast(features, LockLoss::kTooFewMatches, true);
    return;
  }
  // Step 6: the definitive motion from all matches.
  PlanarMotion motion = Fit(features, visible, matches);
  if (!paper) {
    matches = KeepWithinGate(features, visible, std::move(matches), motion);
    if (static_cast<int>(matches.size()) < options_.min_matches ||
        static_cast<double>(matches.size()) < needed) {
      Coast(features, LockLoss::kTooFewMatches, true);
      return;
    }
    motion = Fit(features, visible, matches);
  }
  if (!SmoothContinuation(motion)) {
    Coast(features, LockLoss::kMotionJump, true);
    return;
  }
  std::vector<uint8_t> matched(features.size(), 0);
  double residual2 = 0.0;
  for (const Match& m : matches) {
    residual2 += (features[m.first].position_m -
                  motion.Apply(tracks_[visible[m.second]].filter.position_m())).squaredNorm();
  }
  result_.matched = static_cast<int>(matches.size());
  result_.residual_rms_m = std::sqrt(residual2 / static_cast<double>(matches.size()));
  for (Track& t : tracks_) t.filter.Predict(motion, r1_), ++t.misses;
  for (const Match& m : matches) {
    Track& t = tracks_[visible[m.second]];
    t.filter.Update(features[m.first].position_m, r2_);
    t.characteristics = Of(features[m.first]);
    t.misses = 0;
    ++t.observations;
    result_.track_of_feature[m.first] = t.id;
    matched[m.first] = 1;
  }
  result_.locked = true;
  result_.loss = LockLoss::kNone;
  result_.motion = motion;
  result_.pose = Compose(result_.pose, motion);
  MapRows(features, motion.t_m.norm());
  last_motion_ = motion;
  smoothed_t_m_ += options_.translation_smoothing * (motion.t_m - smoothed_t_m_);
  DropLostTracks();
  StartTracks(features, matched);
}

void FeatureTracker::Coast(std::span<const Feature> features, LockLoss loss, bool add_tracks) {
  const PlanarMotion coast = CoastingMotion();
  for (Track& t : tracks_) t.filter.Predict(coast, r1_), ++t.misses;
  result_.locked = false;
  result_.loss = loss;
  result_.motion = coast;
  result_.pose = Compose(result_.pose, coast);
  // A frame that did not lock maps nothing (it may be a duplicate, or of
  // another place); the distance still counts.
  if (loss != LockLoss::kFirstFrame) MapRows({}, coast.t_m.norm());
  DropLostTracks();
  result_.new_track_of_feature.assign(features.size(), -1);
  if (add_tracks) StartTracks(features, std::vector<uint8_t>(features.size(), 0));
}

void FeatureTracker::StartTracks(std::span<const Feature> features,
                                 const std::vector<uint8_t>& matched) {
  result_.new_track_of_feature = result_.track_of_feature;
  for (size_t i = 0; i < features.size(); ++i) {
    if (matched[i]) continue;
    tracks_.push_back({next_id_, FeatureFilter(features[i].position_m, p0_), Of(features[i]), 0, 1});
    result_.new_track_of_feature[i] = next_id_++;
  }
}

void FeatureTracker::DropLostTracks() {
  std::erase_if(tracks_, [&](const Track& t) {
    return t.misses > options_.max_misses || !InView(t.filter.position_m());
  });
}

}  // namespace plantscale::motion
