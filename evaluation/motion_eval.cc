#include "evaluation/motion_eval.h"

#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <unordered_map>

#include "engine/motion/visual_odometry.h"
#include "engine/pipeline/motion_fusion.h"
#include "evaluation/seeds.h"

namespace plantscale::app {
namespace {

using motion::Feature;
using motion::PlanarMotion;
using motion::VehiclePose2;

// What a feature is in truth: the plant under its pixel and its field
// position on the plane at that plant's height; a feature on no plant
// (kOnGround: a stone, a clod or a shadow's edge the segmenter took for
// plant matter) at its ground point, which a right match keeps as a plant's
// would.
constexpr int kOnGround = -2;
struct FeatureTruth {
  int plant_id = -1;  // -1: unknown (the pixel sees no ground)
  Eigen::Vector2d field_m{0.0, 0.0};
};

VehiclePose2 ToVehiclePose(const sim::Pose2& p) { return {p.heading_rad, {p.x_m, p.y_m}}; }

// The plant a feature lies on: the most frequent instance within 1 px of
// its pixel, else within kTruthRadiusPx. A feature is a boundary pixel of
// the segmented blob, and the segmenter's blob reaches past the rendered
// plant's pixels (its blurred rim): on `field`, tuning seeds 1–4 with the
// wheels' prior, 85 of 1240 matched features had no plant within 1 px and
// 33 within 2 px (session 33); with 1 px alone all their matches were
// scored wrong. The nearer window first, so that a feature between two
// plants keeps the one it touches.
constexpr int kTruthRadiusPx = 2;

int InstanceAt(const cv::Mat& instances, const Eigen::Vector2d& uv) {
  const int u0 = static_cast<int>(uv.x()), v0 = static_cast<int>(uv.y());
  for (int radius = 1; radius <= kTruthRadiusPx; ++radius) {
    std::map<int, int> votes;
    for (int dv = -radius; dv <= radius; ++dv) {
      for (int du = -radius; du <= radius; ++du) {
        const int u = u0 + du, v = v0 + dv;
        if (u < 0 || v < 0 || u >= instances.cols || v >= instances.rows) continue;
        const int k = instances.at<uint16_t>(v, u);
        if (k > 0) ++votes[k];
      }
    }
    int best = 0, count = 0;
    for (const auto& [k, n] : votes) {
      if (n > count) best = k, count = n;
    }
    if (best > 0) return best;
  }
  return 0;
}

// `camera`: the frame's own, bounce and all (Simulator::CameraFor). Placed
// with the nominal camera, the truth itself moved with the bounce (about
// 12 mm from frame to frame on `field`), and a right match was scored
// wrong once the two frames' bounce put it beyond the tolerance: on held-out
// field seeds with the soil's prior 79.2 % right, 97.2 % placed truly
// (session 34).
FeatureTruth TruthOf(const Feature& f, const sim::SimFrame& frame,
                     const geometry::CameraModel& camera,
                     const std::unordered_map<int, const sim::PlantTruth*>& by_instance) {
  FeatureTruth t;
  const auto it = by_instance.find(InstanceAt(frame.rendered.instances, f.pixel));
  const bool on_plant = it != by_instance.end();
  const auto g = camera.ImageToPlane(f.pixel, on_plant ? it->second->height_m : 0.0);
  if (!g) return t;
  t.plant_id = on_plant ? it->second->plant_id : kOnGround;
  t.field_m = ToVehiclePose(frame.truth.pose).ToWorld(*g);
  return t;
}

// r, t taking points of the previous vehicle frame to the current one.
PlanarMotion TrueMotion(const sim::Pose2& previous, const sim::Pose2& current) {
  std::vector<Eigen::Vector2d> from, to;
  for (const Eigen::Vector2d& offset : {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0),
                                       Eigen::Vector2d(0, 1)}) {
    const Eigen::Vector2d field = Eigen::Vector2d(current.x_m, current.y_m) + offset;
    from.push_back(sim::FieldToVehicle(previous, field));
    to.push_back(sim::FieldToVehicle(current, field));
  }
  return motion::FitRigidMotion(from, to);
}

struct Totals {
  int pairs = 0, locked = 0, matches = 0, correct = 0, frames = 0, on_ground = 0;
  double rotation_sq = 0.0, translation_sq = 0.0, drift_sum = 0.0, seconds = 0.0;
  double along_sum = 0.0, across_sum = 0.0;
  int sequences = 0;
  double soil_scale_sum = 0.0;
  int prior_valid = 0, prior_turns = 0;
  double prior_sq = 0.0, prior_psi_sq = 0.0;
  std::vector<double> rms, spacings, angles;
};

class MethodRun {
 public:
  MethodRun(const MotionMethodOptions& o, const geometry::CameraModel& camera,
            motion::MosaicOptions mosaic, double tolerance_m)
      : extractor_(o.features), tracker_(o.tracker, camera, o.features.plane_height_m),
        mosaic_((mosaic.plane_height_m = o.mosaic_plane_height_m, mosaic), camera),
        tolerance_m_(tolerance_m), last_t_m_(o.tracker.initial_motion.t_m) {}

  // Search around the wheels' motion since the previous frame (a track of
  // `track_width_m`, the rotation's σ per frame `psi_sd_rad`).
  void UseWheelPrior(double track_width_m, double psi_sd_rad) {
    track_width_m_ = track_width_m;
    prior_psi_sd_rad_ = psi_sd_rad;
  }
  // Search around the ground's motion between the frames (no odometry).
  void UseImagePrior(const motion::GroundShiftOptions& o, const geometry::CameraModel& camera,
                     double psi_sd_rad) {
    ground_shift_.emplace(o, camera);
    prior_psi_sd_rad_ = psi_sd_rad;
  }
  // Place the features with the camera's pitch the soil reads (`o` with
  // measure_pitch), the prior whatever else it is.
  void UsePitchOnly(const motion::GroundShiftOptions& o, const geometry::CameraModel& camera) {
    pitch_only_.emplace(o, camera);
  }
  // The locked translation scaled by the soil's distance over the features'
  // (the soil's shift lies on the ground; the features on the profile's plane).
  void UseSoilScale(double min_distance_m) {
    pipeline::MotionFusionOptions o;
    o.scale_min_distance_m = min_distance_m;
    soil_scale_.emplace(o);
  }

  // `camera` is the engine's (the calibrated, nominal one); `true_camera`
  // the frame's as it was, bounce and all, which places the truth.
  void Step(const sim::SimFrame& frame, const vision::Segmentation& seg,
            const geometry::CameraModel& camera, const geometry::CameraModel& true_camera,
            const std::unordered_map<int, const sim::PlantTruth*>& by_instance, Totals& totals) {
    if (ground_shift_) SetImagePrior(frame, seg, totals);
    if (pitch_only_) pitch_rad_ = pitch_only_->Update(frame.rendered.image, seg.mask).pitch_rad;
    // Placed with the camera's pitch the soil measured (0 without), as the
    // soil's translation, the search's prior, has it taken out.
    const auto& features = extractor_.Extract(seg.blobs, motion::WithPitch(camera, pitch_rad_));
    if (track_width_m_ > 0.0 && !first_) SetWheelPrior(frame);
    const auto start = std::chrono::steady_clock::now();
    const motion::FrameMotion& m = tracker_.Update(features);
    totals.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!first_) last_t_m_ = m.motion.t_m;
    ++totals.frames;
    ScoreMatches(features, m, frame, true_camera, by_instance, totals);
    if (!first_) pose_ = motion::Compose(pose_, Scaled(m));
    if (first_) {
      first_pose_ = frame.truth.pose;
      first_distance_ = frame.truth.distance_m;
    } else {
      ScoreMotion(m, frame, totals);
    }
    first_ = false;
    previous_pose_ = frame.truth.pose;
    previous_utime_ = frame.truth.utime;
    last_distance_ = frame.truth.distance_m;
    cv::Mat labels;
    motion::LabelFrame(seg.mask, seg.blobs,
                       [&](const vision::Blob& b) { return extractor_.IsPlant(b); }, labels);
    mosaic_.AddFrame(labels, pose_);
  }

  // Drift of the composed pose and the row fit of the mosaic.
  void Finish(const motion::RowFitOptions& rows, Totals& totals) const {
    const VehiclePose2 first = ToVehiclePose(first_pose_);
    const Eigen::Vector2d truth = first.FromWorld({previous_pose_.x_m, previous_pose_.y_m});
    const double distance = last_distance_ - first_distance_;
    if (distance > 0.0) {
      // Vehicle frame: x across (right), y along the forward axis.
      const Eigen::Vector2d error = pose_.position_m - truth;
      totals.drift_sum += 100.0 * error.norm() / distance;
      totals.along_sum += 100.0 * error.y() / distance;
      totals.across_sum += 100.0 * error.x() / distance;
    }
    ++totals.sequences;
    totals.soil_scale_sum += soil_scale_ ? soil_scale_->ratio() : 1.0;
    const motion::MosaicMap map = mosaic_.Build();
    std::vector<Eigen::Vector2d> plants;
    for (const auto& p : map.plants) plants.push_back(p.position_m);
    const motion::RowFit fit = motion::FitRows(plants, 0.5 * pose_.position_m.y(), rows);
    for (const auto& r : fit.rows) totals.rms.push_back(r.rms_m);
    totals.spacings.insert(totals.spacings.end(), fit.spacings_m.begin(), fit.spacings_m.end());
    totals.angles.insert(totals.angles.end(), fit.angles_rad.begin(), fit.angles_rad.end());
  }

 private:
  // The mean measured wheel speeds over the frame's odometry samples.
  void SetWheelPrior(const sim::SimFrame& frame) {
    if (frame.odometry.empty()) return;
    double left = 0.0, right = 0.0;
    for (const sim::OdometrySample& o : frame.odometry) left += o.left_m_s, right += o.right_m_s;
    const double n = static_cast<double>(frame.odometry.size());
    const double dt = 1e-6 * static_cast<double>(frame.truth.utime - previous_utime_);
    const double v = 0.5 * (left + right) / n, w = (right - left) / n / track_width_m_;
    tracker_.SetMotionPrior({-w * dt, {0.0, -v * dt}}, prior_psi_sd_rad_);
  }

  void SetImagePrior(const sim::SimFrame& frame, const vision::Segmentation& seg, Totals& totals) {
    const motion::GroundShift shift = ground_shift_->Update(frame.rendered.image, seg.mask);
    // A step longer than the soil's view can measure (a narrow view at
    // speed): the peak found is another shift's, and ours searches as without.
    const bool usable = shift.valid && !first_ && ground_shift_->CanMeasure(last_t_m_);
    soil_shift_m_ = usable && shift.source == motion::GroundShiftSource::kSoil ? shift.t_m.norm() : -1.0;
    pitch_rad_ = shift.pitch_rad;
    if (!usable) return;
    tracker_.SetMotionPrior({shift.psi_rad, shift.t_m}, prior_psi_sd_rad_);
    const PlanarMotion truth = TrueMotion(previous_pose_, frame.truth.pose);
    ++totals.prior_valid;
    totals.prior_sq += (shift.t_m - truth.t_m).squaredNorm();
    if (shift.turn_valid) {
      ++totals.prior_turns;
      totals.prior_psi_sq += std::pow(motion::WrapAngle(shift.psi_rad - truth.psi_rad), 2);
    }
  }

  // The frame's motion for the pose: a locked one's translation scaled by
  // the soil's distance over the features' (learnt on the locked frames
  // with a soil shift); a coasting one is the prior's, unscaled.
  PlanarMotion Scaled(const motion::FrameMotion& m) {
    PlanarMotion out = m.motion;
    if (!soil_scale_ || !m.locked) return out;
    if (soil_shift_m_ >= 0.0) soil_scale_->Add(soil_shift_m_, m.motion.t_m.norm(), 1.0);
    out.t_m *= soil_scale_->ratio();
    return out;
  }

  void ScoreMatches(std::span<const Feature> features, const motion::FrameMotion& m,
                    const sim::SimFrame& frame, const geometry::CameraModel& camera,
                    const std::unordered_map<int, const sim::PlantTruth*>& by_instance,
                    Totals& totals) {
    std::unordered_map<int64_t, FeatureTruth> next;
    for (size_t i = 0; i < features.size(); ++i) {
      const FeatureTruth now = TruthOf(features[i], frame, camera, by_instance);
      if (m.track_of_feature[i] >= 0) {
        const FeatureTruth& before = track_truth_[m.track_of_feature[i]];
        ++totals.matches;
        if (now.plant_id == kOnGround || before.plant_id == kOnGround) ++totals.on_ground;
        if (now.plant_id != -1 && now.plant_id == before.plant_id &&
            (now.field_m - before.field_m).norm() <= tolerance_m_)
          ++totals.correct;
      }
      next[m.new_track_of_feature[i]] = now;
    }
    for (const auto& t : tracker_.tracks()) {
      const auto it = track_truth_.find(t.id);
      if (!next.count(t.id) && it != track_truth_.end()) next[t.id] = it->second;
    }
    track_truth_ = std::move(next);
  }

  void ScoreMotion(const motion::FrameMotion& m, const sim::SimFrame& frame, Totals& totals) const {
    const PlanarMotion truth = TrueMotion(previous_pose_, frame.truth.pose);
    ++totals.pairs;
    totals.locked += m.locked ? 1 : 0;
    totals.rotation_sq += std::pow(motion::WrapAngle(m.motion.psi_rad - truth.psi_rad), 2);
    totals.translation_sq += (m.motion.t_m - truth.t_m).squaredNorm();
  }

  motion::FeatureExtractor extractor_;
  motion::FeatureTracker tracker_;
  motion::Mosaic mosaic_;
  double tolerance_m_;
  std::unordered_map<int64_t, FeatureTruth> track_truth_;
  sim::Pose2 previous_pose_, first_pose_;
  int64_t previous_utime_ = 0;
  double track_width_m_ = 0.0, prior_psi_sd_rad_ = 0.0;
  std::optional<motion::GroundShiftEstimator> ground_shift_, pitch_only_;
  std::optional<pipeline::VisualScale> soil_scale_;
  double soil_shift_m_ = -1.0;  // this frame's soil shift, -1 for none
  double pitch_rad_ = 0.0;      // the camera's pitch the soil measured
  // The previous frame's motion, locked or coasted (before the first pair:
  // the nominal advance the tracker starts from).
  Eigen::Vector2d last_t_m_;
  VehiclePose2 pose_;           // the motions composed, Scaled
  double first_distance_ = 0.0, last_distance_ = 0.0;
  bool first_ = true;
};

// What ours searches around (options.prior), and with the soil the
// camera's pitch and scale as `out` says they apply.
void UsePrior(const MotionEvalOptions& options, const MotionEvaluation& out, double track_width_m,
              double feature_plane_m, const geometry::CameraModel& camera, MethodRun& run) {
  if (options.prior == MotionPrior::kWheels) {
    run.UseWheelPrior(track_width_m, options.prior_psi_sd_rad);
    if (out.camera_pitch) run.UsePitchOnly(motion::GroundShiftOptions::Soil(), camera);
  } else if (options.prior == MotionPrior::kImage) {
    motion::GroundShiftOptions g = options.ground_shift;
    g.measure_pitch = g.measure_pitch && out.camera_pitch;
    if (g.source == motion::GroundShiftSource::kPlants) {
      g.plane_height_m = feature_plane_m;
    } else if (g.plants_fallback_height_m < 0.0) {
      g.plants_fallback_height_m = feature_plane_m;
    }
    run.UseImagePrior(g, camera, options.prior_psi_sd_rad);
    if (out.soil_scale) run.UseSoilScale(options.soil_scale_min_distance_m);
  }
}

double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

MotionMethodEvaluation Summarise(const std::string& name, const Totals& t) {
  MotionMethodEvaluation e;
  e.method = name;
  e.pairs = t.pairs;
  e.locked_pairs = t.locked;
  e.matches = t.matches;
  e.correct_matches = t.correct;
  e.correct_correspondence_rate = t.matches > 0 ? static_cast<double>(t.correct) / t.matches : 0.0;
  e.matches_on_ground = t.on_ground;
  e.rotation_rmse_deg = t.pairs > 0 ? std::sqrt(t.rotation_sq / t.pairs) * 180.0 / M_PI : 0.0;
  e.translation_rmse_m = t.pairs > 0 ? std::sqrt(t.translation_sq / t.pairs) : 0.0;
  e.drift_cm_per_m = t.sequences > 0 ? t.drift_sum / t.sequences : 0.0;
  e.drift_along_cm_per_m = t.sequences > 0 ? t.along_sum / t.sequences : 0.0;
  e.drift_across_cm_per_m = t.sequences > 0 ? t.across_sum / t.sequences : 0.0;
  e.rows_fitted = static_cast<int>(t.rms.size());
  e.row_fit_rms_m = Mean(t.rms);
  e.row_angle_deg = Mean(t.angles) * 180.0 / M_PI;
  e.row_spacing_m = Mean(t.spacings);
  e.row_rms_m = t.rms;
  e.row_spacings_m = t.spacings;
  e.ms_per_frame = t.frames > 0 ? 1000.0 * t.seconds / t.frames : 0.0;
  e.prior_valid_pairs = t.prior_valid;
  e.prior_translation_rmse_m = t.prior_valid > 0 ? std::sqrt(t.prior_sq / t.prior_valid) : 0.0;
  e.prior_turn_pairs = t.prior_turns;
  e.soil_scale = t.sequences > 0 ? t.soil_scale_sum / t.sequences : 1.0;
  e.prior_rotation_rmse_deg = t.prior_turns > 0 ? std::sqrt(t.prior_psi_sq / t.prior_turns) * 180.0 / M_PI : 0.0;
  return e;
}

}  // namespace

const char* MotionPriorName(MotionPrior p) {
  switch (p) {
    case MotionPrior::kWheels: return "wheels";
    case MotionPrior::kImage: return "image";
    case MotionPrior::kNone: break;
  }
  return "none";
}

OptionErrors MotionEvalOptions::Validate() const {
  OptionErrors e = Prefixed("sim", sim.Validate());
  RequirePositive(e, "seeds", seeds);
  if (frames < 2) e.push_back({"frames", "must be >= 2"});
  RequirePositive(e, "match_tolerance_m", match_tolerance_m);
  RequirePositive(e, "mosaic_resolution_m", mosaic_resolution_m);
  RequirePositive(e, "prior_psi_sd_rad", prior_psi_sd_rad);
  RequirePositive(e, "soil_scale_min_distance_m", soil_scale_min_distance_m);
  for (OptionError& g : Prefixed("ground_shift", ground_shift.Validate())) e.push_back(std::move(g));
  for (const auto& [name, m] : {std::pair{"paper", &paper}, std::pair{"ours", &ours}}) {
    const std::string prefix = name;
    auto f = Prefixed(prefix + ".features", m->features.Validate());
    auto t = Prefixed(prefix + ".tracker", m->tracker.Validate());
    e.insert(e.end(), f.begin(), f.end());
    e.insert(e.end(), t.begin(), t.end());
  }
  auto r = Prefixed("rows", rows.Validate());
  e.insert(e.end(), r.begin(), r.end());
  return e;
}

MotionMethodOptions PaperMethod() {
  MotionMethodOptions m;
  m.features.plane_height_m = 0.0;  // z_vc = v: features on the ground (§3.2)
  m.mosaic_plane_height_m = 0.0;    // images placed on the ground (§5)
  m.tracker.method = motion::MotionMethod::kPaper;
  return m;
}

MotionMethodOptions OursMethod(const sim::SimulatorOptions& sim) {
  MotionMethodOptions m;
  // The contour is the rim of the crop's leaves: the feature plane is the
  // camera's virtual ground plane when configured, else the crop's nominal
  // rim height (radius × height ratio).
  m.features.plane_height_m = sim.camera.virtual_plane_height_m > 0.0
                                  ? sim.camera.virtual_plane_height_m
                                  : sim.field.crop_radius_m * sim.field.crop_height_ratio;
  m.tracker.method = motion::MotionMethod::kOurs;
  // The plant pixels of a bowl-shaped plant are its leaf surface, from the
  // soil up to the rim: on average half the rim height.
  m.mosaic_plane_height_m = 0.5 * m.features.plane_height_m;
  m.tracker.min_matches = 2;  // ψ comes with its prior: two features fix the translation
  m.features.weed_plane_height_m = sim.field.weed_radius_median_m * sim.field.weed_height_ratio;
  m.features.crop_height_per_radius = sim.field.crop_height_ratio;
  // Sharper dominant points only: blunt lobe tips slide along the contour
  // from frame to frame by 2–3 cm (measured: 4 of 263 matches on seeds 1–8).
  m.features.min_sharpness_rad = 1.1;
  m.features.weed_height_per_radius = sim.field.weed_height_ratio;
  return m;
}

MotionEvaluation EvaluateMotion(const MotionEvalOptions& options) {
  ThrowIfInvalid("MotionEvalOptions", options.Validate());
  MotionEvaluation out;
  out.preset = options.sim.preset;
  out.paper_in_table = options.paper_in_table;
  out.frames = options.frames;
  out.true_row_spacing_m = options.sim.field.row_spacing_m;
  out.prior = options.prior;
  out.ground_shift_source = options.ground_shift.source;
  out.soil_scale = options.prior == MotionPrior::kImage && options.soil_scale &&
                   options.ground_shift.source == motion::GroundShiftSource::kSoil;
  // The pitch is the soil's: with the plant masks as the image prior there is none.
  out.camera_pitch = options.camera_pitch && (options.prior == MotionPrior::kWheels ||
                                              (options.prior == MotionPrior::kImage &&
                                               options.ground_shift.source == motion::GroundShiftSource::kSoil));
  const double step_m = options.sim.vehicle.speed_m_s / options.sim.vehicle.frame_rate_hz;
  Totals paper, ours;
  vision::SegmenterOptions seg_options = options.segmenter;
  seg_options.blobs.trace_contours = true;
  // The features are the contours' dominant points, the notches between
  // leaves among them: closing them cost correct correspondences on set-up
  // 2 (ours 98.9 → 97.6 %, the paper's 94.2 %). Growth inside the hulls
  // and into the soil fills the same notches.
  seg_options.close_notches_px = 0;
  seg_options.hull_gain = 0.0;
  seg_options.soil_growth.z = 0.0;
  if (options.sim.render.kind == sim::ImageKind::kRgb) {
    // Colour frames: excess green and Otsu, as `plantscale segment` does.
    seg_options.method = vision::ThresholdMethod::kOtsu;
    seg_options.otsu_floor = 127.5 + 127.5 * 0.05;
  }
  ForEachSeed(options.sim, options.seeds, [&](int, sim::SimulatorOptions& so) {
    so.length_m = step_m * (options.frames + 2) + 1.0;
    sim::Simulator simulator(so);
    vision::Segmenter segmenter(seg_options);
    const geometry::CameraModel& camera = simulator.camera();
    motion::MosaicOptions mosaic;
    mosaic.resolution_m = options.mosaic_resolution_m;
    mosaic.min_m = {-1.5, -1.0};
    mosaic.max_m = {1.5, so.length_m + 1.0};
    // Smoothness of motion needs a first motion: the nominal forward
    // advance per frame (a set speed, not odometry).
    MotionMethodOptions paper_o = options.paper, ours_o = options.ours;
    for (MotionMethodOptions* m : {&paper_o, &ours_o}) m->tracker.initial_motion.t_m = {0.0, -step_m};
    MethodRun paper_run(paper_o, camera, mosaic, options.match_tolerance_m);
    if (options.prior != MotionPrior::kNone) motion::UsePriorSearch(ours_o.tracker, ours_o.features);
    MethodRun ours_run(ours_o, camera, mosaic, options.match_tolerance_m);
    UsePrior(options, out, so.vehicle.track_width_m, ours_o.features.plane_height_m, camera, ours_run);
    sim::SimFrame frame;
    double first = -1.0, last = 0.0;
    for (int k = 0; k < options.frames && simulator.Next(frame); ++k) {
      if (first < 0.0) first = frame.truth.distance_m;
      last = frame.truth.distance_m;
      const vision::Segmentation& seg = segmenter.Process(frame.rendered.image, camera);
      std::unordered_map<int, const sim::PlantTruth*> by_instance;
      for (const auto& p : frame.truth.plants) by_instance[p.instance] = &p;
      const geometry::CameraModel true_camera = simulator.CameraFor(frame.truth.bounce);
      paper_run.Step(frame, seg, camera, true_camera, by_instance, paper);
      ours_run.Step(frame, seg, camera, true_camera, by_instance, ours);
    }
    out.distance_m += (last - first) / options.seeds;
    paper_run.Finish(options.rows, paper);
    ours_run.Finish(options.rows, ours);
  });
  out.seeds = options.seeds;
  out.paper = Summarise("paper", paper);
  out.ours = Summarise("ours", ours);
  return out;
}

}  // namespace plantscale::app
