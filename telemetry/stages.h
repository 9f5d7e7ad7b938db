#pragma once
// The stages that publish what exists today: heartbeat, camera thumbnails,
// odometry, and the simulator's ground truth on its own channels.

#include <deque>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/treatment/treatment_system.h"
#include "engine/vision/segmenter.h"
#include "telemetry/runner.h"
#include "telemetry/types.h"

namespace plantscale::telemetry {

// Heartbeat (PLANTSCALE_HEALTH, every frame offered; the publisher's rate
// sends 2 Hz). Frame rate over the last `window` frames of message time.
class HealthStage : public Stage {
 public:
  std::string name() const override { return "health"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  std::deque<int64_t> frame_utimes_;
};

struct ThumbnailOptions {
  int width_px = 160;  // height keeps the aspect ratio
  int jpeg_quality = 60;

  OptionErrors Validate() const;
};

// Plant segmentation of every frame (engine/vision): keeps the latest blob
// list for the stages after it (thumbnail now; tracker and classifier next).
// With a calibrated camera the blobs are projected onto its virtual ground
// plane (the tracker needs that).
class SegmentationStage : public Stage {
 public:
  explicit SegmentationStage(const vision::SegmenterOptions& options = {},
                             const geometry::CameraModel* camera = nullptr);
  std::string name() const override { return "segmentation"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
  std::span<const vision::Blob> blobs() const { return blobs_; }
  // The blobs the tracker measures (vision::Segmentation::track_blobs).
  std::span<const vision::Blob> track_blobs() const { return track_blobs_; }
  const cv::Mat& mask() const { return mask_; }  // the blobs' plant mask (empty: none)

 private:
  vision::Segmenter segmenter_;
  const geometry::CameraModel* camera_;
  std::span<const vision::Blob> blobs_, track_blobs_;
  cv::Mat mask_;
};

// The crop-grid tracker (engine/tracking) on the segmentation's blobs and
// the frame's odometry: grid state with covariance on PLANTSCALE_GRID every
// frame; refused input and loss of the grid are reported as faults.
class TrackerStage : public Stage {
 public:
  TrackerStage(const geometry::CameraModel& camera, const tracking::TrackerOptions& options,
               const SegmentationStage& segmentation);
  std::string name() const override { return "tracker"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
  const tracking::GridTracker& tracker() const { return tracker_; }
  bool initialised_now() const { return initialised_now_; }  // on the last frame

 private:
  tracking::GridTracker tracker_;
  bool initialised_now_ = false;
  const SegmentationStage& segmentation_;
  std::vector<tracking::Feature> features_;
};

// Downscaled JPEG of the camera frame (PLANTSCALE_THUMBNAIL, 2 Hz) with the
// blobs of `segmentation` when given. Encodes only when the channel's rate
// slot is due.
class ThumbnailStage : public Stage {
 public:
  explicit ThumbnailStage(const ThumbnailOptions& options,
                          const SegmentationStage* segmentation = nullptr);
  std::string name() const override { return "thumbnail"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  ThumbnailOptions options_;
  const SegmentationStage* segmentation_;
};

// Latest wheel odometry with the integrated distance (PLANTSCALE_ODOMETRY).
class OdometryStage : public Stage {
 public:
  std::string name() const override { return "odometry"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  int64_t last_utime_ = -1;
};

// Classification, treatment map and nozzle scheduling (engine/treatment) on
// the tracker's grid and the segmentation's blobs: plants with class and
// why on PLANTSCALE_PLANTS (changed records, 2.5 Hz), nozzle states and finished shots on
// PLANTSCALE_NOZZLES each frame, map tiles on PLANTSCALE_MAP_TILES once the
// bar has passed them. Positions are in the bed frame (treatment/bed_frame.h).
// The scheduler ticks once per odometry sample; the tracker has already
// taken the whole batch, so each tick's pose is dead-reckoned back from the
// tracker's latest at the measured speed. `sink` (a spray bar) gets every
// tick's open mask, all closed on fail-safe.
class TreatmentStage : public Stage {
 public:
  TreatmentStage(const geometry::CameraModel& camera, const treatment::TreatmentOptions& options,
                 const SegmentationStage& segmentation, const TrackerStage& tracker,
                 treatment::NozzleSink sink = {});
  std::string name() const override { return "treatment"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
  // The run is over: one last plant list (the records changed since the
  // previous one, and the plants the bar never reached, WHY_NOT_REACHED),
  // then the tile rows the bar has not passed, up to the last one the camera
  // saw, which are final too.
  void Finish(int64_t utime, Publisher& publisher) override;
  const treatment::TreatmentSystem& system() const { return system_; }

 private:
  void Tick(const sim::OdometrySample& o, RunStatus& status);
  // The last tick's opened and closed nozzles into the shots.
  void RecordShots(int64_t utime);
  void PublishPlants(const VehicleFrame& frame, const treatment::FrameTreatment& t,
                     Publisher& publisher);
  void PublishNozzles(int64_t utime, Publisher& publisher);
  void PublishTiles(int64_t utime, Publisher& publisher, bool to_the_end = false);
  bool TileRowObserved(int tile_row) const;
  // The plants sprayed since the last call join the changed records.
  void NoteNewlySprayed();
  // The changed record ids, sorted and unique; the list starts again.
  std::vector<int> TakeChangedPlants();
  // The spray bar's bed y: the vehicle's, less the bar's offset behind it.
  double BarY() const;

  treatment::TreatmentSystem system_;
  const SegmentationStage& segmentation_;
  const TrackerStage& tracker_;
  std::vector<tracking::Feature> features_;
  std::vector<int> blob_of_feature_;
  treatment::TickResult last_tick_;
  std::vector<int64_t> open_since_;       // per nozzle, −1 closed
  std::vector<Eigen::Vector2d> open_sum_; // per nozzle, sum of strip centres
  std::vector<int> open_ticks_;
  std::vector<NozzleShot> shots_;         // finished since the last message
  int next_tile_row_ = 0;
  int tile_revision_ = 0;
  std::vector<int> changed_plants_;  // record ids since the last plant list
  int64_t last_plants_utime_ = -1;
  int64_t last_frame_index_ = 0;     // of the last frame processed
};

// Simulator ground truth: grid state on PLANTSCALE_SIM_TRUTH and pose on
// PLANTSCALE_SIM_TRUTH_POSE; never on the tracker's channels.
class SimTruthStage : public Stage {
 public:
  std::string name() const override { return "sim_truth"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
};

}  // namespace plantscale::telemetry
