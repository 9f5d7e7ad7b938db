#pragma once
// Frame-to-frame correspondence and motion recovery (Sanchiz & Pla §3.4,
// fig. 4) over per-feature Kalman filters (§4), with the absolute pose by
// composition (eq. 4). No odometry: the only motion prior is the previous
// frame-to-frame motion (smoothness of motion).
//
// Two methods share the stages (correspondence.h):
//   kPaper: steps 1–6 as published: epipolar ellipse, two-way matches,
//           Hough clustering, Umeyama, depth/direction filter (30 %, 5°),
//           greedy final matching by similarity, Umeyama again.
//   kOurs:  the same first two steps, then residual gates instead of the
//           depth/direction cone (which admits a wide wedge of wrong
//           matches), greedy final matching on residual plus similarity,
//           a refit without outliers, tight filter noise, and a
//           row-following motion prior: the rotation ψ is fused with
//           ψ_prior = κ·(H − H_rows) (H the heading from the first frame,
//           H_rows the rows' heading fitted to the crop plants mapped so far,
//           row_heading.h, which the vehicle steers back to), because with the small
//           overlap of consecutive frames the features span a few
//           centimetres and ψ alone is not observable to the 0.01° per
//           frame that 1 cm/m of drift needs. Coasting uses the smoothed
//           translation.
// Bad frames (no features, duplicates, a frame whose features fit no
// motion) lose lock: the pose and the tracks coast on the previous motion,
// and the next good pair locks again.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/motion/correspondence.h"
#include "engine/motion/feature_filter.h"
#include "engine/motion/features.h"
#include "engine/motion/planar_motion.h"
#include "engine/motion/row_heading.h"

namespace plantscale::motion {

enum class MotionMethod { kPaper, kOurs };
const char* Name(MotionMethod method);

struct TrackerOptions {
  MotionMethod method = MotionMethod::kOurs;
  double depth_tolerance = 0.3;                          // §3.2 and step 4: ±30 %
  double direction_tolerance_rad = 5.0 * M_PI / 180.0;   // step 4: 5°
  double search_margin_m = 0.03;                         // widening of the search ellipse
  HoughOptions hough;
  double residual_gate_m = 0.012;   // kOurs: match residual against the fitted motion
  // kOurs with a motion prior (SetMotionPrior): candidates farther than this
  // from where the prior puts the track are not matches, and the nearer
  // and more similar the better (distance plus similarity_weight_m × eq. 6).
  double prior_gate_m = 0.015;
  double similarity_weight_m = 0.01;   // kOurs: metres of residual worth one radian of eq. 6
  int min_matches = 3;              // fewer final matches lose lock
  // kOurs: candidates less similar than this are not matches (eq. 6, rad),
  // and fewer matches than this fraction of min(features, tracks in view)
  // lose lock
  // (a frame of some other place matches a few tracks by chance only).
  double max_similarity_distance = 0.6;
  double min_matched_fraction = 0.3;
  double rotation_prior_sigma_rad = 0.2 * M_PI / 180.0;  // kOurs: σ of ψ about ψ_prior
  double heading_return_per_frame = 0.05;               // kOurs: κ
  // kOurs: H_rows from the mapped crop plants (false: H_rows = 0, the first
  // frame's heading).
  bool fit_row_heading = true;
  RowHeadingOptions row_heading;
  double translation_smoothing = 0.3;   // kOurs: weight of a new t in the coasting motion
  double max_motion_change_m = 0.12;  // a jump in t from the previous frame loses lock
  double max_rotation_change_rad = 5.0 * M_PI / 180.0;
  int max_misses = 3;               // a track unobserved this many frames is dropped
  double view_margin_px = 4.0;      // tracks projecting outside the image are not matched
  double track_sigma_m = 0.02;      // kPaper: σ of P₀ = R₁ = R₂ (eq. 23)
  double process_sigma_m = 0.002;   // kOurs: R₁
  double measurement_sigma_m = 0.003;  // kOurs: P₀ = R₂
  PlanarMotion initial_motion;      // motion assumed before the first locked pair

  OptionErrors Validate() const;
};

enum class LockLoss {
  kNone,
  kFirstFrame,      // nothing to match yet
  kNoFeatures,      // the frame has no plant features
  kDuplicateFrame,  // the same features as the previous frame
  kNoTracks,        // no track in view (all features new)
  kTooFewMatches,   // fewer than min_matches coherent matches
  kMotionJump,      // the fitted motion is not a smooth continuation
};
const char* Name(LockLoss loss);

struct Track {
  int64_t id = 0;
  FeatureFilter filter;
  Characteristics characteristics;  // of the last observation
  int misses = 0;
  int observations = 1;
};

struct FrameMotion {
  bool locked = false;
  LockLoss loss = LockLoss::kFirstFrame;
  PlanarMotion motion;  // r_{k,k−1}, t_{k,k−1} used (coasted when not locked)
  VehiclePose2 pose;    // R_k, T_k in the first frame's vehicle frame
  int candidates = 0;   // two-way matches (step 1)
  int coherent = 0;     // after the Hough selection (step 2)
  int matched = 0;      // final matches (0 when not locked)
  double residual_rms_m = 0.0;  // of the final matches against the motion
  std::vector<int64_t> track_of_feature;  // matched track id, or −1 (new track)
  std::vector<int64_t> new_track_of_feature;  // track id each feature now feeds
};

class FeatureTracker {
 public:
  FeatureTracker(const TrackerOptions& options, const geometry::CameraModel& camera,
                 double plane_height_m);

  const FrameMotion& Update(std::span<const Feature> features);
  // The motion expected for the next frame from another source (the
  // wheels, the grid tracker's prediction): for that one Update, the search
  // regions, the clustering's ψ range, the rotation prior and the coasting
  // use it instead of the smoothed motion and the rows' heading; its
  // rotation weighs σ = psi_sd_rad against the fit's. kOurs only.
  void SetMotionPrior(const PlanarMotion& prior, double psi_sd_rad);
  const std::vector<Track>& tracks() const { return tracks_; }
  const VehiclePose2& pose() const { return result_.pose; }
  // The rows' heading the rotation prior returns to (0 for kPaper or
  // without fit_row_heading, which map no rows).
  double row_heading_rad() const { return row_heading_rad_; }
  const RowHeadingFit& row_fit() const { return row_fit_; }
  const TrackerOptions& options() const { return options_; }

 private:
  bool IsDuplicate(std::span<const Feature> features) const;
  bool InView(const Eigen::Vector2d& p_m) const;
  std::vector<Match> Correspond(std::span<const Feature> features, const std::vector<int>& visible);
  std::vector<Match> FinalMatches(std::span<const Feature> features, const std::vector<int>& visible,
                                  std::vector<Match> matches, const PlanarMotion& motion) const;
  PlanarMotion Fit(std::span<const Feature> features, const std::vector<int>& visible,
                   const std::vector<Match>& matches) const;
  std::vector<Match> KeepWithinGate(std::span<const Feature> features,
                                    const std::vector<int>& visible, std::vector<Match> matches,
                                    const PlanarMotion& motion) const;
  bool SmoothContinuation(const PlanarMotion& motion) const;
  // Step 1's dissimilarity with a motion prior: distance from where the
  // prior puts the track plus the weighted similarity (kNoMatch beyond the gate).
  double PriorCost(const Feature& f, const Track& t, double similarity) const;
  // The rotation expected before looking at the frame.
  double PriorPsi() const;
  // The motion to coast on when not locked.
  PlanarMotion CoastingMotion() const;
  void Advance(std::span<const Feature> features, const std::vector<int>& visible,
               const std::vector<Match>& matches);
  void Coast(std::span<const Feature> features, LockLoss loss, bool add_tracks);
  void StartTracks(std::span<const Feature> features, const std::vector<uint8_t>& matched);
  void DropLostTracks();
  // Maps the crop blobs' features at the current pose into the row fit.
  void MapRows(std::span<const Feature> features, double driven_m);

  TrackerOptions options_;
  geometry::CameraModel camera_;
  Eigen::Matrix3d plane_to_image_;
  Eigen::Matrix2d p0_, r1_, r2_;
  std::vector<Track> tracks_;
  std::vector<Eigen::Vector2d> last_positions_;
  PlanarMotion last_motion_;
  std::optional<PlanarMotion> frame_prior_;  // SetMotionPrior, for one Update
  double frame_prior_psi_sd_rad_ = 0.0;
  Eigen::Vector2d smoothed_t_m_{0.0, 0.0};
  FrameMotion result_;
  double view_along_m_;           // the image's footprint along y on the feature plane
  RowHeading rows_;
  RowHeadingFit row_fit_;         // rows_.fit() after the last frame
  double row_heading_rad_ = 0.0;  // rows_.heading_rad() after the last frame
  bool first_mapped_ = false;
  int64_t next_id_ = 1;
  bool first_ = true;
};

}  // namespace plantscale::motion
