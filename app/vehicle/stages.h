#pragma once
// The vehicle process's stages: the pipeline with what it publishes,
// segmentation alone (an uncalibrated camera), heartbeat, camera
// thumbnails, odometry, and the simulator's ground truth on its own channels.

#include <deque>

#include <span>

#include "app/vehicle/runner.h"
#include "engine/common/options.h"
#include "engine/geometry/camera_model.h"
#include "engine/pipeline/pipeline.h"
#include "engine/vision/segmenter.h"
#include "telemetry/log.h"
#include "telemetry/types.h"

namespace plantscale::vehicle {

// Heartbeat (PLANTSCALE_HEALTH, every frame offered; the publisher's rate
// sends 2 Hz). Frame rate over the last `window` frames of message time.
// A fault line stays in the heartbeat for `hold_us` of message time after
// the frame it was last seen in, so that a fault of a frame or two (a
// refused odometry sample, a corrupt frame) reaches the 2 Hz heartbeat and
// the log; lines that differ only in their numbers are one fault, shown as
// last seen.
class HealthStage : public Stage {
 public:
  explicit HealthStage(int64_t hold_us = 1'000'000) : hold_us_(hold_us) {}
  std::string name() const override { return "health"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  std::vector<std::string> HeldFaults(int64_t utime, const std::vector<std::string>& now);

  int64_t hold_us_;
  std::deque<int64_t> frame_utimes_;
  struct Held {
    std::string key;   // the line without its numbers
    std::string line;  // as last seen
    int64_t utime;     // last seen
  };
  std::vector<Held> held_;  // in order of first appearance
};

// The vehicle's records: a log that cannot be written (disk full) and
// messages the transport could not send (the station's network gone) are
// fault lines while they last and `hold_us` after; the log's stopping and
// starting again are events (the second one reaches the log, with what was
// not logged). `log` may be null (no --log). Add it before HealthStage.
class RecordsStage : public Stage {
 public:
  explicit RecordsStage(const telemetry::LoggingTransport* log, int64_t hold_us = 2'000'000)
      : log_(log), hold_us_(hold_us) {}
  std::string name() const override { return "records"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  void LogFaults(const VehicleFrame& frame, RunStatus& status, Publisher& publisher);

  const telemetry::LoggingTransport* log_;
  int64_t hold_us_;
  int64_t log_failures_ = 0, log_resumed_ = 0;
  int64_t resumed_utime_ = -1;
  int64_t not_logged_at_resume_ = 0;
};

struct ThumbnailOptions {
  int width_px = 160;  // height keeps the aspect ratio
  int jpeg_quality = 60;

  OptionErrors Validate() const;
};

// The blobs of the frame being processed, for the stages after the one
// that segmented it (thumbnails).
class BlobView {
 public:
  virtual ~BlobView() = default;
  virtual std::span<const vision::Blob> blobs() const = 0;
};

// Plant segmentation alone, for a camera without calibration (`run` without
// --calibration): the thumbnails' blobs, no tracking or treatment.
class SegmentationStage : public Stage, public BlobView {
 public:
  explicit SegmentationStage(const vision::SegmenterOptions& options = {});
  std::string name() const override { return "segmentation"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
  std::span<const vision::Blob> blobs() const override { return blobs_; }

 private:
  vision::Segmenter segmenter_;
  std::span<const vision::Blob> blobs_;
};

// Downscaled JPEG of the camera frame (PLANTSCALE_THUMBNAIL, 2 Hz) with the
// blobs of `segmentation` when given. Encodes only when the channel's rate
// slot is due.
class ThumbnailStage : public Stage {
 public:
  explicit ThumbnailStage(const ThumbnailOptions& options, const BlobView* blobs = nullptr);
  std::string name() const override { return "thumbnail"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  ThumbnailOptions options_;
  const BlobView* blobs_;
};

// Latest wheel odometry with the integrated distance (PLANTSCALE_ODOMETRY).
class OdometryStage : public Stage {
 public:
  std::string name() const override { return "odometry"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;

 private:
  int64_t last_utime_ = -1;
};

// The vehicle pipeline (engine/pipeline) on every frame and its odometry,
// in time order, and what it knows on the telemetry: the grid at the
// frame's capture with its covariance on PLANTSCALE_GRID; plants with class
// and why on PLANTSCALE_PLANTS (changed records, 2 Hz); nozzle states and
// finished shots on PLANTSCALE_NOZZLES each frame; map tiles on
// PLANTSCALE_MAP_TILES once the bar has passed them. Positions are in the
// bed frame (treatment/bed_frame.h). The operator's commands (RunStatus)
// hold the bar or change the mode; the pipeline's faults and the bar's
// fail-safe go into RunStatus. `sink` (a spray bar) gets every tick's open
// mask, all closed on fail-safe.
class PipelineStage : public Stage, public BlobView {
 public:
  PipelineStage(const geometry::CameraModel& camera, const pipeline::PipelineOptions& options,
                treatment::NozzleSink sink = {});
  std::string name() const override { return "pipeline"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
  // The run is over: one last plant list (the records changed since the
  // previous one, and the plants the bar never reached, WHY_NOT_REACHED),
  // then the tile rows the bar has not passed, up to the last one the camera
  // saw, which are final too.
  void Finish(int64_t utime, Publisher& publisher) override;
  std::span<const vision::Blob> blobs() const override { return blobs_; }
  const pipeline::Pipeline& pipeline() const { return pipeline_; }
  // Every scheduler tick of the frame processed last, in time order.
  const std::vector<treatment::TickResult>& ticks() const { return ticks_; }

 private:
  void PublishGrid(const pipeline::FrameResult& r, Publisher& publisher);
  void ReportTicks(RunStatus& status);
  // An event when the bar closes on the plants' uncertain position
  // (treatment::kPositionUncertain) and when it is lifted.
  void ReportUncertainty(int64_t utime, Publisher& publisher);
  // The tick's opened and closed nozzles into the shots.
  void RecordShots(const treatment::TickResult& tick);
  void PublishPlants(const VehicleFrame& frame, const treatment::FrameTreatment& t,
                     Publisher& publisher);
  void PublishNozzles(int64_t utime, Publisher& publisher);
  void PublishTiles(int64_t utime, Publisher& publisher, bool to_the_end = false);
  bool TileRowObserved(int tile_row) const;
  int LastObservedTileRow() const;
  bool learned_reported_ = false;  // the model's load failure was an event
  telemetry::MapTileDelta Tile(int tx, int ty) const;
  // The plants sprayed since the last call join the changed records.
  void NoteNewlySprayed();
  // The changed record ids, sorted and unique; the list starts again.
  std::vector<int> TakeChangedPlants();
  // The spray bar's bed y: the vehicle's, less the bar's offset behind it.
  double BarY() const;
  const treatment::TreatmentSystem& system() const { return *pipeline_.treatment(); }

  pipeline::Pipeline pipeline_;
  std::span<const vision::Blob> blobs_;
  std::vector<treatment::TickResult> ticks_;  // this frame's
  treatment::TickResult last_tick_;
  bool ticked_ = false;
  std::vector<int64_t> open_since_;       // per nozzle, −1 closed
  std::vector<Eigen::Vector2d> open_sum_; // per nozzle, sum of strip centres
  std::vector<int> open_ticks_;
  std::vector<telemetry::NozzleShot> shots_;  // finished since the last message
  int next_tile_row_ = 0;
  int tile_revision_ = 0;
  std::vector<int> changed_plants_;  // record ids since the last plant list
  int64_t last_plants_utime_ = -1;
  int64_t last_frame_index_ = 0;     // of the last frame processed
  int slip_bursts_ = 0;              // the slip guard's, as last reported
  bool uncertain_ = false;           // the bar is closed on kPositionUncertain
};

// Simulator ground truth: grid state on PLANTSCALE_SIM_TRUTH and pose on
// PLANTSCALE_SIM_TRUTH_POSE; never on the tracker's channels.
class SimTruthStage : public Stage {
 public:
  std::string name() const override { return "sim_truth"; }
  void Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) override;
};

}  // namespace plantscale::vehicle
