#include "telemetry/stages.h"

#include <plantscale_lcmtypes/plantscale_command_t.hpp>

#include <algorithm>
#include <cmath>
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
  track_blobs_ = {};
  mask_ = cv::Mat();
  if (frame.image.empty()) return;
  try {
    const vision::Segmentation& seg =
        camera_ ? segmenter_.Process(frame.image, *camera_) : segmenter_.Process(frame.image);
    blobs_ = seg.blobs;
    track_blobs_ = seg.track_blobs;
    mask_ = seg.mask;
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
  tracking::FeaturesFromBlobs(segmentation_.track_blobs(), frame.image.cols, frame.image.rows,
                              features_, tracker_.centroid_heights());
  const tracking::FrameReport r =
      tracker_.ProcessFrame(frame.utime, frame.image.cols, frame.image.rows, features_);
  if (!r.input.accepted) status.faults.push_back("tracker: " + r.input.reason);
  initialised_now_ = r.initialised_now;
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

namespace {

constexpr int kTileCells = 64;
constexpr int64_t kPlantListPeriodUs = 500'000;

uint8_t TileCell(treatment::CellClass c) {
  switch (c) {
    case treatment::CellClass::kCrop: return plantscale_map_tile_t::CELL_CROP;
    case treatment::CellClass::kWeed: return plantscale_map_tile_t::CELL_WEED;
    case treatment::CellClass::kSoil: break;
  }
  return plantscale_map_tile_t::CELL_SOIL;
}

int WhyCode(const treatment::PlantRecord& r) {
  if (r.crop()) return plantscale_plant_t::WHY_CROP_IN_REGION;
  if (r.small) return plantscale_plant_t::WHY_TOO_SMALL;
  return plantscale_plant_t::WHY_OUTSIDE_REGION;
}

PlantObservation Observation(const treatment::PlantRecord& r, int why) {
  PlantObservation p;
  p.id = r.id;
  p.kind = r.crop() ? PlantKind::kCrop : PlantKind::kWeed;
  p.position_m = r.bed_m;
  p.size_m2 = r.area_m2;
  p.sprayed = r.sprayed;
  p.why = why;
  p.distance_to_crop_m = std::isfinite(r.distance_m) ? r.distance_m : -1.0;
  return p;
}

}  // namespace

TreatmentStage::TreatmentStage(const geometry::CameraModel& camera,
                               const treatment::TreatmentOptions& options,
                               const SegmentationStage& segmentation, const TrackerStage& tracker,
                               treatment::NozzleSink sink)
    : system_(camera, options, std::move(sink)), segmentation_(segmentation), tracker_(tracker) {
  const auto n = static_cast<size_t>(options.scheduler.bar.nozzles);
  open_since_.assign(n, -1);
  open_sum_.assign(n, Eigen::Vector2d::Zero());
  open_ticks_.assign(n, 0);
}

void TreatmentStage::Tick(const sim::OdometrySample& o, RunStatus& status) {
  const tracking::GridTracker& tracker = tracker_.tracker();
  const double speed = 0.5 * (o.left_m_s + o.right_m_s);
  const bool odometry_ok = std::isfinite(speed) && std::abs(speed) <=
                                                       tracker.options().max_wheel_speed_m_s;
  const treatment::BedPose pose = treatment::TrackerPose(tracker, o.utime, odometry_ok);
  treatment::SafetyInputs safety;
  safety.pose_utime = std::min(tracker.utime(), o.utime);
  safety.last_frame_utime = system_.last_frame_utime();
  safety.odometry_valid = odometry_ok;
  safety.tracking = tracker.mode() == tracking::TrackerMode::kTracking;
  safety.held = status.commands.held();
  const int8_t mode = status.commands.mode;
  if (mode != 0) {
    system_.set_mode(mode == plantscale_command_t::MODE_SPRAY_WEED ? treatment::SprayMode::kWeed
                                                                   : treatment::SprayMode::kCrop);
  }
  // The scheduler's ticks until the next pose, each led from this one.
  bool failsafe = false;
  for (const treatment::TickResult& tick : system_.TicksFrom(o.utime, pose, safety)) {
    last_tick_ = tick;
    failsafe |= tick.fail_reasons != 0;
    RecordShots(tick.utime);
  }
  status.failsafe = failsafe;
  // The tracker reports its own loss; before the first frame the bar is
  // closed by design, not by a fault.
  if (safety.last_frame_utime >= 0) {
    for (const std::string& m : last_tick_.messages) {
      if (m.rfind("tracker", 0) != 0 && m.rfind("held", 0) != 0) {
        status.faults.push_back("treatment: bar closed: " + m);
      }
    }
  }
}

void TreatmentStage::RecordShots(int64_t utime) {
  std::vector<Eigen::Vector2d> centre(open_since_.size(), Eigen::Vector2d::Zero());
  for (const treatment::NozzleTarget& t : last_tick_.opened) {
    centre[static_cast<size_t>(t.nozzle)] = {0.5 * (t.x0 + t.x1), 0.5 * (t.y0 + t.y1)};
  }
  for (size_t i = 0; i < open_since_.size(); ++i) {
    const bool open = (last_tick_.open_mask >> i) & 1u;
    if (open) {
      if (open_since_[i] < 0) open_since_[i] = utime, open_sum_[i].setZero(), open_ticks_[i] = 0;
      open_sum_[i] += centre[i];
      ++open_ticks_[i];
    } else if (open_since_[i] >= 0) {
      shots_.push_back({static_cast<int>(i), open_since_[i], utime,
                        open_sum_[i] / std::max(1, open_ticks_[i]), -1});
      open_since_[i] = -1;
    }
  }
}

void TreatmentStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  for (const sim::OdometrySample& o : frame.odometry) Tick(o, status);
  if (frame.image.empty()) return;
  const std::span<const vision::Blob> blobs = segmentation_.blobs();
  tracking::FeaturesFromBlobs(blobs, frame.image.cols, frame.image.rows, features_,
                              tracker_.tracker().centroid_heights());
  treatment::FeatureBlobIndices(blobs, blob_of_feature_);
  tracking::FrameReport report;
  report.mode = tracker_.tracker().mode();
  report.initialised_now = tracker_.initialised_now();
  const treatment::FrameTreatment& t = system_.OnFrame(frame.utime, tracker_.tracker(), report,
                                                       blobs, features_, blob_of_feature_,
                                                       segmentation_.mask());
  if (t.map_reset) next_tile_row_ = 0;
  last_frame_index_ = frame.frame_index;
  PublishPlants(frame, t, publisher);
  PublishNozzles(frame.utime, publisher);
  PublishTiles(frame.utime, publisher);
}

// Plants whose record changed since the last message, every 0.5 s of
// message time (the list is the largest channel: it must fit the budget),
// leaving out records seen only once (leaf fragments, noise).
void TreatmentStage::PublishPlants(const VehicleFrame& frame, const treatment::FrameTreatment& t,
                                   Publisher& publisher) {
  if (t.map_reset) changed_plants_.clear();
  NoteNewlySprayed();
  if (!t.classified) return;
  changed_plants_.insert(changed_plants_.end(), t.plant_ids.begin(), t.plant_ids.end());
  if (last_plants_utime_ >= 0 && frame.utime - last_plants_utime_ < kPlantListPeriodUs) return;
  std::vector<PlantObservation> plants;
  for (int id : TakeChangedPlants()) {
    if (id < 0) continue;
    const treatment::PlantRecord& r = system_.registry().records()[static_cast<size_t>(id)];
    if (r.confirmed()) plants.push_back(Observation(r, WhyCode(r)));
  }
  last_plants_utime_ = frame.utime;
  publisher.Publish(channels::kPlants, ToLcm(plants, frame.utime, frame.frame_index));
}

void TreatmentStage::PublishNozzles(int64_t utime, Publisher& publisher) {
  NozzleBar bar;
  for (size_t i = 0; i < open_since_.size(); ++i) {
    bar.open.push_back(((last_tick_.open_mask >> i) & 1u) != 0);
  }
  bar.fault.assign(open_since_.size(), plantscale_nozzles_t::FAULT_NONE);
  bar.failsafe = last_tick_.fail_reasons != 0;
  bar.shots = std::move(shots_);
  shots_.clear();
  publisher.Publish(channels::kNozzles, ToLcm(bar, utime));
}

// The run's end: the plant records changed since the last list, and every
// plant the mode would spray that the bar had not yet reached, so that the
// station, log and report tell them from misses; then the last tile rows.
void TreatmentStage::Finish(int64_t utime, Publisher& publisher) {
  const double bar_y = BarY();
  const bool spray_crop = system_.options().scheduler.mode == treatment::SprayMode::kCrop;
  NoteNewlySprayed();
  const std::vector<int> ids = TakeChangedPlants();
  std::vector<PlantObservation> plants;
  const std::vector<treatment::PlantRecord>& records = system_.registry().records();
  for (const treatment::PlantRecord& r : records) {
    if (!r.confirmed()) continue;
    const bool target = r.crop() == spray_crop;
    const bool not_reached = target && !r.sprayed && r.bed_m.y() > bar_y;
    const bool changed = std::binary_search(ids.begin(), ids.end(), r.id);
    if (not_reached || changed)
      plants.push_back(Observation(r, not_reached ? plantscale_plant_t::WHY_NOT_REACHED : WhyCode(r)));
  }
  if (!plants.empty()) publisher.PublishFinal(channels::kPlants, ToLcm(plants, utime, last_frame_index_));
  PublishTiles(utime, publisher, true);
}

void TreatmentStage::NoteNewlySprayed() {
  const std::vector<int> sprayed = system_.TakeNewlySprayed();
  changed_plants_.insert(changed_plants_.end(), sprayed.begin(), sprayed.end());
}

std::vector<int> TreatmentStage::TakeChangedPlants() {
  std::vector<int> ids = std::move(changed_plants_);
  changed_plants_.clear();
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

double TreatmentStage::BarY() const {
  return tracker_.tracker().forward_distance_m() - system_.options().scheduler.bar.bar_offset_m;
}

bool TreatmentStage::TileRowObserved(int tile_row) const {
  const treatment::TreatmentMap& map = system_.map();
  for (int r = tile_row * kTileCells; r < std::min(map.rows(), (tile_row + 1) * kTileCells); ++r) {
    for (int c = 0; c < map.columns(); ++c) {
      if (map.Observed(c, r)) return true;
    }
  }
  return false;
}

// A tile row is sent once the bar has passed it: its cells are final. At
// the end of the run, every row up to the last the camera saw.
void TreatmentStage::PublishTiles(int64_t utime, Publisher& publisher, bool to_the_end) {
  const tracking::GridTracker& tracker = tracker_.tracker();
  if (!to_the_end && tracker.mode() != tracking::TrackerMode::kTracking) return;
  const treatment::TreatmentMap& map = system_.map();
  const double bar_y = BarY();
  const double edge = kTileCells * map.options().cell_m;
  int last_seen = -1;  // the last tile row with a cell the camera saw
  if (to_the_end) {
    for (int row = map.rows() / kTileCells - 1; row >= next_tile_row_; --row) {
      if (TileRowObserved(row)) {
        last_seen = row;
        break;
      }
    }
  }
  const auto due = [&](int row) {
    if ((row + 1) * kTileCells > map.rows()) return false;
    return to_the_end ? row <= last_seen : map.options().start_y_m + (row + 1) * edge < bar_y;
  };
  while (due(next_tile_row_)) {
    for (int tx = 0; tx * kTileCells < map.columns(); ++tx) {
      MapTileDelta d;
      d.tile_x = tx;
      d.tile_y = next_tile_row_;
      d.revision = tile_revision_;
      d.origin_m = {map.origin_x_m() + tx * edge, map.options().start_y_m + next_tile_row_ * edge};
      d.resolution_m = map.options().cell_m;
      d.width = d.height = kTileCells;
      d.cells.reserve(static_cast<size_t>(kTileCells * kTileCells));
      for (int j = 0; j < kTileCells; ++j) {
        for (int i = 0; i < kTileCells; ++i) {
          const int c = tx * kTileCells + i;
          const int r = next_tile_row_ * kTileCells + j;
          const treatment::CellClass cls = c < map.columns() ? map.ClassOf(c, r) : treatment::CellClass::kSoil;
          d.cells.push_back(c >= map.columns() ? plantscale_map_tile_t::CELL_UNKNOWN
                            : map.Treated(c, r) ? plantscale_map_tile_t::CELL_TREATED
                            : cls == treatment::CellClass::kSoil && !map.Observed(c, r)
                                ? plantscale_map_tile_t::CELL_UNKNOWN
                                : TileCell(cls));
        }
      }
      publisher.Publish(channels::kMapTiles, ToLcm(d, utime));
    }
    ++next_tile_row_;
  }
  ++tile_revision_;
}

}  // namespace plantscale::telemetry
