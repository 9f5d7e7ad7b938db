#pragma once
// The stages that publish what exists today: heartbeat, camera thumbnails,
// odometry, and the simulator's ground truth on its own channels.

#include <deque>

#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/tracking/grid_tracker.h"
#include "engine/vision/segmenter.h"
#include "telemetry/runner.h"

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

 private:
  vision::Segmenter segmenter_;
  const geometry::CameraModel* camera_;
  std::span<const vision::Blob> blobs_;
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

 private:
  tracking::GridTracker tracker_;
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

// Simulator ground truth: grid state on PLANTSCALE_SIM_TRUTH and pose on
// PLANTSCALE_SIM_TRUTH_POSE; never on the tracker's channels.
class SimTruthStage : public Stage {
 public:
  std::string name() const override { return "sim_truth"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
};

}  // namespace plantscale::telemetry
