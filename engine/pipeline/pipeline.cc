#include "engine/pipeline/pipeline.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>

#include "engine/tracking/blob_features.h"

namespace plantscale::pipeline {

namespace {

std::string Seconds(int64_t us) {
  std::ostringstream out;
  out.precision(3);
  out << std::fixed << 1e-6 * static_cast<double>(us) << " s";
  return out.str();
}

}  // namespace

OptionErrors LearnedOptions::Validate() const {
  // The spec is checked as the model loads: a model that does not load
  // leaves the grid's rule rather than stopping the vehicle.
  OptionErrors e;
  if (!(tracker_drops_weeds_at >= 0.0)) {
    e.push_back({"tracker_drops_weeds_at", "must be >= 0 (> 1: never)"});
  }
  return e;
}

OptionErrors PipelineOptions::Validate() const {
  OptionErrors e = Prefixed("segmenter", segmenter.Validate());
  for (OptionError& m : Prefixed("learned", learned.Validate())) e.push_back(std::move(m));
  const OptionErrors t = Prefixed("tracker", tracker.Validate());
  e.insert(e.end(), t.begin(), t.end());
  if (treat) {
    const OptionErrors r = Prefixed("treatment", treatment.Validate());
    e.insert(e.end(), r.begin(), r.end());
  }
  RequirePositive(e, "max_odometry_age_s", max_odometry_age_s);
  RequireFinite(e, "map_keep_behind_bar_m", map_keep_behind_bar_m);
  for (OptionError& m : Prefixed("motion", motion.Validate())) e.push_back(std::move(m));
  if (motion.enabled && !track) e.push_back({"motion.enabled", "needs track on"});
  if (treat && !track) e.push_back({"track", "must be on when treat is (treatment needs the grid)"});
  return e;
}

namespace {

// The fail-safe's margins derived for the crop the tracker is told of
// (TreatmentOptions::UncertaintyMargin), unless set.
PipelineOptions WithCropMargins(PipelineOptions o) {
  treatment::TreatmentOptions& t = o.treatment;
  if (t.close_on_uncertainty && std::isfinite(o.tracker.crop_radius_m)) {
    const Eigen::Vector2d margin = t.UncertaintyMargin(o.tracker.crop_radius_m);
    t.uncertainty_margin_across_m = margin.x();
    t.uncertainty_margin_along_m = margin.y();
  }
  if (o.motion.enabled) o.segmenter.blobs.trace_contours = true;  // the features' contours
  ThrowIfInvalid("pipeline options", o.Validate());
  return o;
}

}  // namespace

Pipeline::Pipeline(const geometry::CameraModel& camera, const PipelineOptions& options,
                   treatment::NozzleSink sink)
    : camera_(camera),
      options_(WithCropMargins(options)),
      segmenter_(options_.segmenter),
      tracker_(camera, options_.tracker),
      visual_scale_(options_.motion),
      disagreement_(options_.motion),
      wheel_guard_(options_.tracker.slip_guard) {
  if (options_.treat) {
    system_ = std::make_unique<treatment::TreatmentSystem>(camera, options_.treatment, std::move(sink));
  }
  if (options_.learned.enabled()) {
    // A model that does not load leaves the thesis's rule: the vehicle runs
    // on, and says so in every frame's faults.
    const LearnedOptions& l = options_.learned;
    const std::string name = l.source.empty() ? std::string("segmenter model") : "segmenter model " + l.source;
    try {
      if (!l.unreadable.empty()) throw DataError(l.unreadable);
      learned_.emplace(*l.onnx, l.spec);
    } catch (const std::exception& e) {
      learned_fault_ = name + ": not loaded (" + e.what() + "); crop and weed by the grid's rule";
    }
  }
  if (options_.motion.enabled) visual_.emplace(camera, options_.motion.visual);
  if (options_.motion.enabled && options_.motion.camera_pitch)
    camera_pitch_.emplace(motion::GroundShiftOptions::Soil(), camera);
}

void Pipeline::set_sink(treatment::NozzleSink sink) {
  if (system_) system_->set_sink(std::move(sink));
}

void Pipeline::SetOperator(bool held, std::optional<treatment::SprayMode> mode) {
  held_ = held;
  if (mode && system_) system_->set_mode(*mode);
}

treatment::SafetyInputs Pipeline::Safety(int64_t pose_utime, bool odometry_ok) const {
  treatment::SafetyInputs s;
  s.pose_utime = pose_utime;
  s.last_frame_utime = system_ ? system_->last_frame_utime() : -1;
  s.camera_ok = !camera_fault_;
  s.odometry_valid = odometry_ok;
  s.tracking = tracker_.mode() == tracking::TrackerMode::kTracking;
  s.held = held_;
  if (system_ && s.tracking) {
    const treatment::PlantReach reach = system_->ReachAtBar(tracker_);
    s.reach_across_m = reach.across_m;
    s.reach_along_m = reach.along_m;
  }
  return s;
}

void Pipeline::KeepTicks(std::span<const treatment::TickResult> ticks) {
  if (!ticks.empty()) last_tick_ = ticks.back();
}

OdometrySample Pipeline::Fused(const OdometrySample& o, int64_t previous_utime) {
  const double scale = tracker_.odometry_scale();
  const double width = options_.tracker.track_width_m;
  const PlanarSpeed wheels = WheelSpeed(o.left_m_s, o.right_m_s, scale, width, options_.motion);
  const motion::VisualMotion* v = visual_->last().valid ? &visual_->last() : nullptr;
  if (v && (o.utime - v->utime) * 1e-6 > options_.motion.max_visual_age_s) v = nullptr;
  const PlanarSpeed camera = v ? Scaled(VisualSpeed(*v), visual_scale_.ratio()) : PlanarSpeed{};
  const bool finite = std::isfinite(o.left_m_s) && std::isfinite(o.right_m_s);
  FusedSpeed f = Fuse(wheels, v && finite ? &camera : nullptr, options_.motion.gate_chi2);
  if (v && finite && visual_scale_.learnt()) {
    disagreement_.Add(v->utime, wheels, camera);
    if (f.source == FusedSource::kFused && disagreement_.wheels_off()) {
      // The wheels at fault: at the camera's scale, weighed with it.
      f = Fuse(disagreement_.Corrected(wheels), &camera, options_.motion.gate_chi2);
      f.source = FusedSource::kCamera;
    }
  }
  if (f.source == FusedSource::kFused && previous_utime >= 0 && o.utime > previous_utime) {
    visual_scale_.Add(wheels.speed_m_s, v->speed_m_s, (o.utime - previous_utime) * 1e-6);
  }
  last_source_ = f.source;
  if (f.source == FusedSource::kWheels) {
    driven_ = wheels;
    return o;
  }
  if (f.source == FusedSource::kCamera) ++camera_substitutions_;
  driven_ = f.speed;
  OdometrySample out = o;
  ToWheels(f.speed, scale, width, out.left_m_s, out.right_m_s);
  return out;
}

const PoseResult& Pipeline::AddOdometry(const OdometrySample& o) {
  const int64_t previous = last_wheel_utime_;
  if (o.utime > last_wheel_utime_) last_wheel_utime_ = o.utime;
  if (!visual_) return DeadReckon(o, options_.tracker.wheel_sd_fraction);
  // The wheels as the tracker's slip guard would read them (a stalled
  // encoder read from the other wheel, a spin held at the ground speed
  // before it), then weighed against the camera: the raw wheels would be
  // refuted by the camera while it is fresh and fed raw when it is not, an
  // alternation in which the tracker's own guard never sees a steady fault.
  // The tracker keeps its guard on the weighed speeds too: the step where
  // the camera takes over from spinning wheels is held there as slip
  // rather than driven on (without it, tuning seeds 1–3, placement over a
  // 30 % spin went 8.7, 14.2, 10.8 → 16.7, 29.5, 20.3 mm and over a 20 %
  // short scale 10.5, 10.8, 9.8 → 17.5, 21.1, 11.9 mm).
  OdometrySample guarded = o;
  const double dt = previous >= 0 && o.utime > previous ? (o.utime - previous) * 1e-6 : 0.0;
  if (std::isfinite(o.left_m_s) && std::isfinite(o.right_m_s)) {
    const tracking::WheelSpeeds w = wheel_guard_.Filter({o.left_m_s, o.right_m_s}, dt);
    guarded.left_m_s = w.left_m_s;
    guarded.right_m_s = w.right_m_s;
  }
  const OdometrySample s = Fused(guarded, previous);
  // The camera's own σ when it stands in; a wheel read from the other with
  // the tracker's wheel-fault σ (the held turn rate is a guess).
  double sd = last_source_ == FusedSource::kCamera
                  ? WheelSdFraction(driven_, options_.tracker.track_width_m)
                  : options_.tracker.wheel_sd_fraction;
  if (last_source_ != FusedSource::kCamera && wheel_guard_.faulty_wheel() != 0) {
    sd = std::hypot(sd, tracking::kWheelFaultSdFraction);
  }
  return DeadReckon(s, sd);
}

const PoseResult& Pipeline::DeadReckon(const OdometrySample& o, double sd_fraction, int ticks) {
  pose_.input = tracker_.AddOdometry(o.utime, o.left_m_s, o.right_m_s, sd_fraction);
  pose_.ticks = {};
  if (o.utime > last_odometry_utime_) last_odometry_utime_ = o.utime;
  if (!system_) return pose_;
  // The pose at the sample's time from the tracker's newest state; a refused
  // sample leaves the wheels unknown (the bar closes on it).
  const bool ok = pose_.input.accepted;
  const treatment::BedPose pose = treatment::TrackerPose(tracker_, o.utime, ok);
  pose_.ticks =
      system_->TicksFrom(o.utime, pose, Safety(std::min(tracker_.utime(), o.utime), ok), ticks);
  KeepTicks(pose_.ticks);
  return pose_;
}

void Pipeline::Refuse(const std::string& why) {
  frame_.accepted = false;
  frame_.faults.push_back(why);
  camera_fault_ = true;
}

const FrameResult& Pipeline::ProcessFrame(int64_t utime, int frame_index, const cv::Mat& image) {
  frame_.utime = utime;
  frame_.frame_index = frame_index;
  frame_.accepted = true;
  frame_.faults.clear();
  frame_.report = {};
  frame_.blobs = {};
  frame_.track_blobs = {};
  frame_.mask = cv::Mat();
  spare_classes_ = std::move(frame_.classes);  // its buffers serve the next model pass
  frame_.classes = {};
  frame_.track_features = {};
  frame_.features = {};
  frame_.blob_of_feature = {};
  frame_.treatment = nullptr;
  frame_.ticks = {};
  frame_.visual = {};
  frame_.visual_substituted = false;
  frame_ticks_.clear();
  if (!learned_fault_.empty()) frame_.faults.push_back(learned_fault_);
  if (image.empty()) {
    Refuse("camera: frame " + std::to_string(frame_index) + " has no image");
  } else if (image.cols != camera_.width() || image.rows != camera_.height()) {
    Refuse("camera: frame " + std::to_string(frame_index) + " is " + std::to_string(image.cols) +
           "x" + std::to_string(image.rows) + " px, the calibration is " +
           std::to_string(camera_.width()) + "x" + std::to_string(camera_.height()) + " px");
  } else if (options_.track && last_frame_utime_ >= 0 && utime <= last_frame_utime_) {
    Refuse("camera: frame " + std::to_string(frame_index) + " out of time order (captured " +
           Seconds(last_frame_utime_ - utime) + " before the previous frame)");
  } else {
    if (learned_) {
      try {
        frame_.classes = std::move(spare_classes_);
        learned_->Classify(image, frame_.classes);
      } catch (const std::exception& e) {  // this frame by the grid's rule
        frame_.classes = {};
        frame_.faults.push_back(std::string("segmenter model: ") + e.what() +
                                "; this frame by the grid's rule");
      }
    }
    try {
      const vision::Segmentation& seg = frame_.classes.classes.empty()
                                            ? segmenter_.Process(image, camera_)
                                            : segmenter_.Process(image, camera_, frame_.classes);
      frame_.blobs = seg.blobs;
      frame_.track_blobs = seg.track_blobs;
      frame_.mask = seg.mask;
      if (!frame_.classes.classes.empty()) KeepTrackBlobs();
    } catch (const std::exception& e) {
      Refuse(std::string("segmentation: ") + e.what());
    }
  }
  if (!options_.track) {
    frame_.mode = tracker_.mode();
    return frame_;
  }
  if (frame_.accepted) UpdateVisualMotion(image);
  if (frame_.accepted) {
    tracking::FeaturesFromBlobs(frame_.track_blobs, image.cols, image.rows, track_features_,
                                tracker_.centroid_heights());
    frame_.track_features = track_features_;
    frame_.report = tracker_.UpdateAtCapture(utime, image.cols, image.rows, track_features_);
    if (!frame_.report.input.accepted) {
      Refuse("tracker: " + frame_.report.input.reason);
    } else {
      last_frame_utime_ = utime;
      camera_fault_ = false;
      if (!frame_.report.input.reason.empty()) frame_.faults.push_back("tracker: " + frame_.report.input.reason);
    }
  }
  frame_.mode = tracker_.mode();
  if (frame_.accepted && frame_.mode == tracking::TrackerMode::kLost) {
    frame_.faults.push_back("tracker: " + frame_.report.skipped_reason);
  }
  // The bed's row spacing disagrees with the crop profile's: a health line
  // while it lasts (the report's row_spacing_mismatch is the event, once).
  if (frame_.accepted && tracker_.row_spacing_mismatch()) {
    frame_.faults.push_back("tracker: " + tracker_.row_spacing_mismatch()->Text());
  }
  frame_.state = tracker_.state();
  frame_.covariance = tracker_.covariance();
  frame_.forward_distance_m = tracker_.forward_distance_m();
  if (frame_.accepted && visual_) KeepGridMotion();
  if (frame_.accepted && system_) Treat();
  tracker_.CatchUp();
  if (system_ && options_.map_keep_behind_bar_m > 0.0 &&
      tracker_.mode() == tracking::TrackerMode::kTracking) {
    system_->ForgetBehind(tracker_.forward_distance_m() -
                          options_.treatment.scheduler.bar.bar_offset_m -
                          options_.map_keep_behind_bar_m);
  }
  CloseIfOdometryStopped();
  frame_.ticks = frame_ticks_;
  return frame_;
}

// The tracker's blobs less those the model is sure are weeds.
void Pipeline::KeepTrackBlobs() {
  track_kept_.clear();
  for (const vision::Blob& b : frame_.track_blobs) {
    const bool weed = b.learned_class == static_cast<int>(vision::PixelClass::kWeed) &&
                      b.learned_confidence >= options_.learned.tracker_drops_weeds_at;
    if (!weed) track_kept_.push_back(b);
  }
  frame_.track_blobs = track_kept_;
}

// The camera's motion since the previous frame; fed to the tracker as the
// odometry of the frame's capture when the wheels have gone silent.
void Pipeline::UpdateVisualMotion(const cv::Mat& image) {
  if (!visual_) return;
  double pitch = 0.0;
  if (camera_pitch_) {
    try {
      pitch = camera_pitch_->Update(image, frame_.mask).pitch_rad;
    } catch (const std::exception& e) {  // an image the soil view cannot read: the nominal camera
      camera_pitch_->Reset();
      frame_.faults.push_back(std::string("camera pitch: ") + e.what());
    }
  }
  const bool silent = last_wheel_utime_ >= 0 &&
                      (frame_.utime - last_wheel_utime_) * 1e-6 > options_.motion.substitute_after_s;
  // The search's prior: the grid's own motion over the last frames (the
  // plants hold it) while the tracker holds the grid, else the speeds
  // driven with. Not the wheels: the search's gate is a few millimetres a
  // frame, and wheels spinning 30 % or reading 20 % short put the prior
  // 12–19 mm off, so the camera found no motion or the wheels' own, and
  // confirmed the fault it is there to refute. Not the camera's last
  // estimate either, whose error the search would carry on from frame to
  // frame once the wheels are silent.
  const std::optional<PlanarSpeed> grid = GridMotion();
  const PlanarSpeed prior = grid ? *grid : driven_;
  frame_.visual = visual_->Update(frame_.utime, frame_.blobs, prior.speed_m_s / visual_scale_.ratio(),
                                  prior.yaw_rate_rad_s, pitch);
  if (!frame_.visual.valid) frame_.faults.push_back("camera motion: " + frame_.visual.reason);
  // The wheels are silent and the camera gave no motion: nothing is fed, so
  // the tracker dead-reckons on its own with the wide noise of silent
  // wheels (GridTracker::PredictTo); a held speed fed as odometry would
  // claim the wheels' precision.
  if (!silent || !frame_.visual.valid || frame_.utime <= tracker_.utime()) return;
  driven_ = Scaled(VisualSpeed(frame_.visual), visual_scale_.ratio());
  const double sd = WheelSdFraction(driven_, options_.tracker.track_width_m);
  last_source_ = FusedSource::kCamera;
  ++camera_substitutions_;
  frame_.visual_substituted = true;
  OdometrySample s;
  s.utime = frame_.utime;
  ToWheels(driven_, tracker_.odometry_scale(), options_.tracker.track_width_m, s.left_m_s,
           s.right_m_s);
  const PoseResult& p = DeadReckon(s, sd, FrameTicks());
  frame_ticks_.insert(frame_ticks_.end(), p.ticks.begin(), p.ticks.end());
  frame_.faults.push_back("odometry: silent; the camera's motion stands in");
}

// Over the longest span of the last frames within a pairable gap (the
// posterior's frame-to-frame wander averages down over it).
std::optional<PlanarSpeed> Pipeline::GridMotion() const {
  const GridAt& b = grid_at_.back();
  for (const GridAt& a : grid_at_) {
    if (a.utime < 0 || b.utime <= a.utime) continue;
    const double dt = (b.utime - a.utime) * 1e-6;
    if (dt > options_.motion.visual.max_frame_gap_s) continue;
    PlanarSpeed s;
    s.speed_m_s = (b.forward_m - a.forward_m) / dt;
    s.yaw_rate_rad_s = (b.bearing_rad - a.bearing_rad) / dt;  // Ψ' = Ψ + the turn
    return s;
  }
  return std::nullopt;
}

void Pipeline::KeepGridMotion() {
  if (tracker_.mode() != tracking::TrackerMode::kTracking) {
    grid_at_.fill(GridAt{});
    return;
  }
  std::rotate(grid_at_.begin(), grid_at_.begin() + 1, grid_at_.end());
  grid_at_.back() = {frame_.utime, tracker_.forward_distance_m(), tracker_.state().bearing_rad};
}

// Ticks from a frame's pose standing in for silent wheels: until the next
// frame is due (the interval since the previous one), at most as long as a
// pose stays fresh (the fail-safe would close the bar on the later ones).
int Pipeline::FrameTicks() const {
  if (!system_) return 0;
  const treatment::SchedulerOptions& o = options_.treatment.scheduler;
  const double span = std::min(frame_.visual.dt_s, o.fail_safe.max_pose_age_s);
  return std::max(o.TicksPerPose(), static_cast<int>(std::floor(span / o.tick_s)));
}

// Classification and mapping with the grid at capture (the tracker holds it
// there until CatchUp).
void Pipeline::Treat() {
  tracking::FeaturesFromBlobs(frame_.blobs, camera_.width(), camera_.height(), features_,
                              tracker_.centroid_heights());
  treatment::FeatureBlobIndices(frame_.blobs, blob_of_feature_);
  frame_.features = features_;
  frame_.blob_of_feature = blob_of_feature_;
  frame_.treatment = &system_->OnFrame(frame_.utime, tracker_, frame_.report, frame_.blobs,
                                       features_, blob_of_feature_, frame_.mask);
}

// No odometry sample ticks the bar when the odometry has stopped: the frame
// commands it closed, odometry invalid, at its capture.
void Pipeline::CloseIfOdometryStopped() {
  if (!system_) return;
  const int64_t age = last_odometry_utime_ < 0 ? -1 : frame_.utime - last_odometry_utime_;
  const bool stopped = last_odometry_utime_ < 0 || age * 1e-6 > options_.max_odometry_age_s;
  if (!stopped) return;
  frame_.faults.push_back(last_odometry_utime_ < 0
                              ? std::string("odometry: none received")
                              : "odometry: stopped " + Seconds(age) + " before the frame");
  if (last_tick_ && last_tick_->utime >= frame_.utime) return;  // ticks stay in time order
  const treatment::BedPose pose = treatment::TrackerPose(tracker_, frame_.utime, false);
  for (const treatment::TickResult& t :
       system_->TicksFrom(frame_.utime, pose, Safety(tracker_.utime(), false))) {
    frame_ticks_.push_back(t);
  }
  KeepTicks(frame_ticks_);
}

const FrameResult& Pipeline::Step(int64_t utime, int frame_index, const cv::Mat& image,
                                  std::span<const OdometrySample> odometry,
                                  std::vector<treatment::TickResult>* ticks) {
  std::vector<std::string> refused;  // the step's odometry the tracker refused, for `faults`
  const auto feed = [&](bool before) {
    for (const OdometrySample& o : odometry) {
      if ((o.utime <= utime) != before) continue;
      const PoseResult& p = AddOdometry(o);
      if (ticks) ticks->insert(ticks->end(), p.ticks.begin(), p.ticks.end());
      if (!p.input.accepted) {
        refused.push_back("odometry: sample at " + Seconds(o.utime - utime) + " from the frame: " +
                          p.input.reason);
      }
    }
  };
  feed(true);
  ProcessFrame(utime, frame_index, image);
  if (ticks) ticks->insert(ticks->end(), frame_.ticks.begin(), frame_.ticks.end());
  feed(false);
  frame_.faults.insert(frame_.faults.end(), refused.begin(), refused.end());
  return frame_;
}

}  // namespace plantscale::pipeline
