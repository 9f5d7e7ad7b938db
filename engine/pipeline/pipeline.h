#pragma once
// The vehicle's frame pipeline, the one composition of the engine that every
// user runs: the vehicle process (`simulate --publish`, `run`), every
// `evaluate` and the whole-frame benchmark. It takes camera frames with
// their capture time and wheel odometry samples, in the order they arrive,
// and runs segmentation, the crop-grid tracker, classification, the
// treatment map and the nozzle scheduler. No transport, no files: results
// come back per frame and per odometry sample, nozzle commands go to a sink.
//
// Time: a frame is classified, placed and mapped with the grid as it stood
// at the frame's capture, whatever odometry came in after the capture
// before the frame did (GridTracker::UpdateAtCapture); the scheduler ticks
// from the newest pose. Faults never throw out of it: a refused frame, a
// lost grid or odometry that stopped is a reported state with the bar
// closed (the scheduler's fail-safe reasons).

#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/motion/ground_shift.h"
#include "engine/motion/visual_odometry.h"
#include "engine/pipeline/motion_fusion.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/treatment/treatment_system.h"
#include "engine/vision/learned_segmenter.h"
#include "engine/vision/segmenter.h"

namespace plantscale::pipeline {

// The grower's learned crop/weed model (learned_segmenter.h), when the crop
// profile names one: its classes cut the plant mask where crop meets weed
// (a weed touching a crop is a blob of its own), and the classifier takes
// a blob's learned class where the model is sure of it
// (ClassifierOptions::learned_min_confidence).
struct LearnedOptions {
  std::shared_ptr<const std::vector<uint8_t>> onnx;  // the model's bytes; null: no model
  vision::LearnedModelSpec spec;                     // from its card
  std::string source;      // where the model came from (its file), for messages
  std::string unreadable;  // why the named model could not be read (the grid's rule then)
  // The tracker measures no blob the model is this sure is a weed (weeds
  // beside the rows pull the grid's lines); > 1: it measures every blob.
  double tracker_drops_weeds_at = 0.8;

  bool enabled() const { return onnx != nullptr || !unreadable.empty(); }
  OptionErrors Validate() const;
};

struct PipelineOptions {
  vision::SegmenterOptions segmenter;
  LearnedOptions learned;
  tracking::TrackerOptions tracker;
  treatment::TreatmentOptions treatment;
  // Off: segmentation and tracking only (no classification, map or bar).
  bool treat = true;
  // Off: segmentation only (needs treat off): frames in any order, no
  // odometry needed (evaluate segmentation's sampled frames).
  bool track = true;
  // A frame captured this long after the newest odometry sample finds the
  // odometry stopped: the bar closes (odometry invalid) until it resumes.
  double max_odometry_age_s = 0.2;
  // The treatment map keeps the bed from this far behind the spray bar on
  // (rows behind the bar are final: sprayed or not, and published); <= 0
  // keeps the whole run (at most 1.3 km of it, TreatmentMap).
  double map_keep_behind_bar_m = 2.0;
  // The camera's own motion as a second motion source (motion_fusion.h).
  // On: the segmenter traces contours, each frame's motion is weighed
  // against the wheels, and it stands in for odometry that stopped.
  MotionFusionOptions motion;

  OptionErrors Validate() const;
};

// A wheel odometry sample: measured ground speeds over the period ending at
// utime (µs, the frames' clock).
struct OdometrySample {
  int64_t utime = 0;
  double left_m_s = 0.0;
  double right_m_s = 0.0;
};

// What one odometry sample did: the tracker's verdict and the scheduler's
// ticks until the next pose (empty without treatment).
struct PoseResult {
  tracking::InputStatus input;
  std::span<const treatment::TickResult> ticks;
};

struct FrameResult {
  int64_t utime = 0;  // capture
  int frame_index = 0;
  // False: the frame was refused (out of time order, no image, the wrong
  // size, segmentation failed); `faults` says why and the bar is closed
  // (camera fault) until a frame is accepted.
  bool accepted = false;
  std::vector<std::string> faults;  // this frame's problems, each prefixed by its part
  tracking::FrameReport report;     // the tracker's
  tracking::TrackerMode mode = tracking::TrackerMode::kInitialising;
  // The grid at capture, with its covariance and the distance driven then.
  geometry::GridState state;
  geometry::Matrix5d covariance = geometry::Matrix5d::Zero();
  double forward_distance_m = 0.0;
  // The segmentation (valid until the next frame): every blob, the blobs the
  // tracker measured, and the plant mask.
  std::span<const vision::Blob> blobs, track_blobs;
  cv::Mat mask;
  // The learned model's classes of the frame (empty without a model, or
  // when it failed on this frame: `faults` says so).
  vision::ClassMaps classes;
  // Features of `track_blobs`, as the tracker measured them.
  std::span<const tracking::Feature> track_features;
  // Features of `blobs` as classified: features[i] from blobs[blob_of_feature[i]].
  std::span<const tracking::Feature> features;
  std::span<const int> blob_of_feature;
  // Classification and mapping (null without treatment or when refused).
  const treatment::FrameTreatment* treatment = nullptr;
  // Ticks the frame itself made: the bar commanded closed when the odometry
  // has stopped (no odometry sample would tick otherwise).
  std::span<const treatment::TickResult> ticks;
  // The camera's motion since the previous frame (valid: false, with the
  // reason, when it gave none or the source is off).
  motion::VisualMotion visual;
  // The camera's motion was fed to the tracker as this frame's odometry
  // (the wheels had gone silent).
  bool visual_substituted = false;
};

class Pipeline {
 public:
  // Throws InvalidOptionsError. The camera must outlive the pipeline.
  Pipeline(const geometry::CameraModel& camera, const PipelineOptions& options,
           treatment::NozzleSink sink = {});

  // A wheel odometry sample: dead reckoning, then the scheduler's ticks.
  const PoseResult& AddOdometry(const OdometrySample& sample);
  // A camera frame captured at utime (CV_8UC1 or CV_8UC3 of the camera's size).
  const FrameResult& ProcessFrame(int64_t utime, int frame_index, const cv::Mat& image);
  // A frame with the odometry that came with it, in time order: the samples
  // up to its capture, the frame, the samples after it. `ticks` (optional)
  // collects every tick of the step. The frame's faults end with one line
  // per odometry sample the tracker refused ("odometry: sample at ...").
  const FrameResult& Step(int64_t utime, int frame_index, const cv::Mat& image,
                          std::span<const OdometrySample> odometry,
                          std::vector<treatment::TickResult>* ticks = nullptr);

  // The operator: `held` closes the bar (pause, spraying off); `mode` (when
  // set) is the spray mode from the next tick on.
  void SetOperator(bool held, std::optional<treatment::SprayMode> mode = std::nullopt);
  void set_sink(treatment::NozzleSink sink);

  const tracking::GridTracker& tracker() const { return tracker_; }
  // Null without treatment.
  const treatment::TreatmentSystem* treatment() const { return system_.get(); }
  treatment::TreatmentSystem* treatment() { return system_.get(); }
  const PipelineOptions& options() const { return options_; }
  // The segmenter, for measuring it (its continuous score: Segmenter::Score).
  vision::Segmenter& segmenter() { return segmenter_; }
  // The learned model runs (the options named one and it loaded).
  bool learned() const { return learned_.has_value(); }
  // Why the model named in the options does not run (it failed to load):
  // the thesis's rule classifies. Empty when it runs or none was named.
  const std::string& learned_fault() const { return learned_fault_; }
  const geometry::CameraModel& camera() const { return camera_; }
  // The newest tick (fail-safe state, open mask), when there was one.
  const std::optional<treatment::TickResult>& last_tick() const { return last_tick_; }
  int64_t last_odometry_utime() const { return last_odometry_utime_; }
  // Which source the last odometry sample was dead-reckoned with, and how
  // many samples the camera stood in for the wheels (disagreeing or silent).
  FusedSource last_motion_source() const { return last_source_; }
  int camera_substitutions() const { return camera_substitutions_; }

 private:
  treatment::SafetyInputs Safety(int64_t pose_utime, bool odometry_ok) const;
  void Refuse(const std::string& why);
  void Treat();
  void CloseIfOdometryStopped();
  void KeepTicks(std::span<const treatment::TickResult> ticks);
  // The speeds the tracker dead-reckons with for a wheel sample.
  OdometrySample Fused(const OdometrySample& wheels, int64_t previous_utime);
  // `ticks`: as TreatmentSystem::TicksFrom's count.
  const PoseResult& DeadReckon(const OdometrySample& s, double sd_fraction, int ticks = 0);
  void UpdateVisualMotion(const cv::Mat& image);
  void KeepTrackBlobs();
  int FrameTicks() const;

  const geometry::CameraModel& camera_;
  PipelineOptions options_;
  vision::Segmenter segmenter_;
  std::optional<vision::LearnedSegmenter> learned_;
  std::string learned_fault_;
  std::vector<vision::Blob> track_kept_;  // track blobs less those the model is sure are weeds
  tracking::GridTracker tracker_;
  std::unique_ptr<treatment::TreatmentSystem> system_;
  bool held_ = false;
  bool camera_fault_ = false;  // the last frame was refused
  int64_t last_frame_utime_ = -1;
  int64_t last_odometry_utime_ = -1;
  std::optional<treatment::TickResult> last_tick_;
  PoseResult pose_;
  FrameResult frame_;
  vision::ClassMaps spare_classes_;  // the previous frame's class maps, reused by the model
  std::vector<tracking::Feature> track_features_, features_;
  std::vector<int> blob_of_feature_;
  std::vector<treatment::TickResult> frame_ticks_;
  std::optional<motion::VisualOdometry> visual_;
  std::optional<motion::GroundShiftEstimator> camera_pitch_;  // options_.motion.camera_pitch
  PlanarSpeed driven_;  // what the tracker last dead-reckoned with (ground)
  FusedSource last_source_ = FusedSource::kWheels;
  int camera_substitutions_ = 0;
  int64_t last_wheel_utime_ = -1;  // newest sample from the wheels themselves
  VisualScale visual_scale_;
  PersistentDisagreement disagreement_;
  tracking::SlipGuard wheel_guard_;  // the raw wheels read before the camera weighs them
  // The grid's motion between the last frames the tracker held it (forward
  // distance and bearing at capture): the camera's search prior.
  struct GridAt {
    int64_t utime = -1;
    double forward_m = 0.0, bearing_rad = 0.0;
  };
  std::array<GridAt, 4> grid_at_{};  // oldest first
  std::optional<PlanarSpeed> GridMotion() const;
  void KeepGridMotion();
};

}  // namespace plantscale::pipeline
