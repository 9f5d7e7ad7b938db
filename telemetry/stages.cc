#include "telemetry/stages.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include "engine/tracking/blob_features.h"
#include "telemetry/channels.h"
#include "telemetry/convert.h"

namespace plantscale::telemetry {

void HealthStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  constexpr size_t kWindow = 25;
  frame_utimes_.push_back(frame.utime);
  while (frame_utimes_.size() > kWindow) frame_utimes_.pop_front();
  Health h;
  h.source = status.source;
  h.boot_utime = status.boot_utime;
  const double span_s = 1e-6 * static_cast<double>(frame_utimes_.back() - frame_utimes_.front());
  h.frame_rate_hz = span_s > 0 ? static_cast<double>(frame_utimes_.size() - 1) / span_s : 0.0;
  h.frames = status.frames;
  h.dropped_frames = status.dropped_frames;
  h.distance_m = status.distance_m;
  h.failsafe = status.failsafe;
  h.faults = status.faults;
  h.telemetry_dropped = publisher.total_dropped();
  publisher.Publish(channels::kHealth, ToLcm(h, frame.utime));
}

OptionErrors ThumbnailOptions::Validate() const {
  OptionErrors errors;
  RequireInRange(errors, "width_px", width_px, 16, 1024);
  RequireInRange(errors, "jpeg_quality", jpeg_quality, 1, 100);
  return errors;
}

SegmentationStage::SegmentationStage(const vision::SegmenterOptions& options,
                                     const geometry::CameraModel* camera)
    : segmenter_(options), camera_(camera) {}

void SegmentationStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher&) {
  blobs_ = {};
  if (frame.image.empty()) return;
  try {
    blobs_ = camera_ ? segmenter_.Process(frame.image, *camera_).blobs
                     : segmenter_.Process(frame.image).blobs;
  } catch (const DataError& e) {
    status.faults.push_back(std::string("segmentation: ") + e.what());
  }
}

ThumbnailStage::ThumbnailStage(const ThumbnailOptions& options,
                               const SegmentationStage* segmentation)
    : options_(options), segmentation_(segmentation) {
  ThrowIfInvalid("thumbnail options", options_.Validate());
}

void ThumbnailStage::Process(const VehicleFrame& frame, RunStatus&, Publisher& publisher) {
  if (frame.image.empty() || !publisher.Due(channels::kThumbnail, frame.utime)) return;
  const double scale = static_cast<double>(options_.width_px) / frame.image.cols;
  cv::Mat small;
  cv::resize(frame.image, small, cv::Size(), scale, scale, cv::INTER_AREA);
  plantscale_thumbnail_t m{};
  m.utime = frame.utime;
  m.frame_index = frame.frame_index;
  m.source_width = static_cast<int16_t>(frame.image.cols);
  m.source_height = static_cast<int16_t>(frame.image.rows);
  m.width = static_cast<int16_t>(small.cols);
  m.height = static_cast<int16_t>(small.rows);
  cv::imencode(".jpg", small, m.jpeg, {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality});
  m.jpeg_size = static_cast<int32_t>(m.jpeg.size());
  if (segmentation_ != nullptr) {
    for (const vision::Blob& b : segmentation_->blobs()) {
      plantscale_blob_t blob{};
      blob.u = static_cast<float>(b.centroid_px.x());
      blob.v = static_cast<float>(b.centroid_px.y());
      blob.area_px = b.area_px;
      blob.cls = 0;  // CLS_UNKNOWN until the classifier (issue 6) runs
      m.blobs.push_back(blob);
    }
  }
  m.num_blobs = static_cast<int32_t>(m.blobs.size());
  publisher.Publish(channels::kThumbnail, std::move(m));
}

void OdometryStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  for (const sim::OdometrySample& s : frame.odometry) {
    if (last_utime_ >= 0) {
      status.distance_m +=
          0.5 * (s.left_m_s + s.right_m_s) * 1e-6 * static_cast<double>(s.utime - last_utime_);
    }
    last_utime_ = s.utime;
  }
  if (frame.odometry.empty()) return;
  const sim::OdometrySample& latest = frame.odometry.back();
  plantscale_odometry_t m{};
  m.utime = latest.utime;
  m.left_m_s = latest.left_m_s;
  m.right_m_s = latest.right_m_s;
  m.distance_m = status.distance_m;
  m.valid = 1;
  publisher.Publish(channels::kOdometry, m);
}

void SimTruthStage::Process(const VehicleFrame& frame, RunStatus&, Publisher& publisher) {
  if (!frame.truth) return;
  publisher.Publish(channels::kSimTruth,
                    TruthToLcm(frame.truth->grid, frame.utime, frame.frame_index));
  const sim::Pose2& p = frame.truth->pose;
  publisher.Publish(channels::kSimTruthPose,
                    ToLcm(Pose{p.x_m, p.y_m, p.heading_rad, Eigen::Matrix3d::Zero()}, frame.utime));
}

TrackerStage::TrackerStage(const geometry::CameraModel& camera,
                           const tracking::TrackerOptions& options,
                           const SegmentationStage& segmentation)
    : tracker_(camera, options), segmentation_(segmentation) {}

void TrackerStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  for (const sim::OdometrySample& o : frame.odometry) {
    const tracking::InputStatus in = tracker_.AddOdometry(o.utime, o.left_m_s, o.right_m_s);
    if (!in.accepted) status.faults.push_back("tracker: " + in.reason);
  }
  if (frame.image.empty()) return;
  tracking::FeaturesFromBlobs(segmentation_.blobs(), frame.image.cols, frame.image.rows,
                              features_);
  const tracking::FrameReport r =
      tracker_.ProcessFrame(frame.utime, frame.image.cols, frame.image.rows, features_);
  if (!r.input.accepted) status.faults.push_back("tracker: " + r.input.reason);
  if (r.mode == tracking::TrackerMode::kLost) {
    status.faults.push_back("tracker: " + r.skipped_reason);
  }
  GridEstimate e;
  e.utime = frame.utime;
  e.frame_index = frame.frame_index;
  e.state = tracker_.state();
  e.covariance = tracker_.covariance();
  switch (r.mode) {
    case tracking::TrackerMode::kInitialising: e.mode = FilterMode::kInitialising; break;
    case tracking::TrackerMode::kLost: e.mode = FilterMode::kLost; break;
    case tracking::TrackerMode::kTracking:
      e.mode = r.updated ? FilterMode::kTracking : FilterMode::kDeadReckoning;
      break;
  }
  for (const tracking::Association& a : r.associations) {
    if (std::find(e.lines_in_view.begin(), e.lines_in_view.end(), a.m) == e.lines_in_view.end()) {
      e.lines_in_view.push_back(a.m);
    }
  }
  std::sort(e.lines_in_view.begin(), e.lines_in_view.end());
  e.observations = static_cast<int>(features_.size());
  e.validated = r.matched;
  e.innovation_nis = r.nis;
  publisher.Publish(channels::kGrid, ToLcm(e));
}

}  // namespace plantscale::telemetry
