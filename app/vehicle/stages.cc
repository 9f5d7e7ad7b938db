#include "app/vehicle/stages.h"

#include <plantscale_lcmtypes/plantscale_command_t.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <plantscale_lcmtypes/plantscale_event_t.hpp>
#include <plantscale_lcmtypes/plantscale_odometry_t.hpp>
#include <plantscale_lcmtypes/plantscale_thumbnail_t.hpp>

#include "telemetry/channels.h"
#include "telemetry/convert.h"

namespace plantscale::vehicle {

namespace channels = telemetry::channels;
using telemetry::FilterMode;
using telemetry::GridEstimate;
using telemetry::Health;
using telemetry::MapTileDelta;
using telemetry::NozzleBar;
using telemetry::PlantKind;
using telemetry::PlantObservation;
using telemetry::ToLcm;

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
  h.faults = HeldFaults(frame.utime, status.faults);
  h.telemetry_dropped = publisher.total_dropped();
  publisher.Publish(channels::kHealth, ToLcm(h, frame.utime));
}

namespace {

// A fault line without its numbers: "no heartbeat for 0.260 s" and "... for
// 0.340 s" are the same fault.
std::string FaultKey(const std::string& line) {
  std::string key;
  for (const char c : line) {
    if (std::isdigit(static_cast<unsigned char>(c)) || (c == '.' && !key.empty() && key.back() == '#')) {
      if (key.empty() || key.back() != '#') key += '#';
    } else {
      key += c;
    }
  }
  return key;
}

}  // namespace

std::vector<std::string> HealthStage::HeldFaults(int64_t utime, const std::vector<std::string>& now) {
  for (const std::string& line : now) {
    const std::string key = FaultKey(line);
    const auto it = std::find_if(held_.begin(), held_.end(), [&](const Held& h) { return h.key == key; });
    if (it == held_.end()) {
      held_.push_back({key, line, utime});
    } else {
      it->line = line;
      it->utime = utime;
    }
  }
  std::erase_if(held_, [&](const Held& h) { return h.utime < utime - hold_us_; });
  std::vector<std::string> lines;
  for (const Held& h : held_) lines.push_back(h.line);
  return lines;
}

namespace {

std::string SecondsText(int64_t us) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f s", 1e-6 * static_cast<double>(us));
  return b;
}

void Event(Publisher& publisher, int64_t utime, const std::string& kind, const std::string& text) {
  plantscale_event_t e{};
  e.utime = utime;
  e.severity = plantscale_event_t::SEVERITY_WARNING;
  e.kind = kind;
  e.text = text;
  publisher.Publish(channels::kEvents, e);
}

}  // namespace

void RecordsStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  if (log_ != nullptr) LogFaults(frame, status, publisher);
  const telemetry::TransportFailures& f = publisher.transport_failures();
  if (f.count > 0 && f.last_utime >= frame.utime - hold_us_) {
    status.faults.push_back("telemetry: " + std::to_string(f.count) +
                            " messages not sent (the log has them), the last " +
                            SecondsText(frame.utime - f.last_utime) + " ago: " + f.last_error);
  }
}

void RecordsStage::LogFaults(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  const telemetry::LogStatus& s = log_->status();
  if (s.failures > log_failures_) {
    log_failures_ = s.failures;
    Event(publisher, frame.utime, "log_failed",
          "log not written from here on (retried every second): " + s.error);
  }
  if (s.resumed > log_resumed_) {
    log_resumed_ = s.resumed;
    resumed_utime_ = frame.utime;
    Event(publisher, frame.utime, "log_resumed",
          "log written again; " + std::to_string(s.not_logged - not_logged_at_resume_) +
              " messages were not logged since " + SecondsText(frame.utime - s.failed_utime) +
              " ago, after: " + s.error);
    not_logged_at_resume_ = s.not_logged;
  }
  if (!s.writing) {
    status.faults.push_back("log: not written for " + SecondsText(frame.utime - s.failed_utime) +
                            ", " + std::to_string(s.not_logged - not_logged_at_resume_) +
                            " messages not logged: " + s.error);
  } else if (resumed_utime_ >= 0 && frame.utime - resumed_utime_ <= hold_us_) {
    status.faults.push_back("log: written again after a write failure: " + s.error);
  }
}

OptionErrors ThumbnailOptions::Validate() const {
  OptionErrors errors;
  RequireInRange(errors, "width_px", width_px, 16, 1024);
  RequireInRange(errors, "jpeg_quality", jpeg_quality, 1, 100);
  return errors;
}

SegmentationStage::SegmentationStage(const vision::SegmenterOptions& options)
    : segmenter_(options) {}

void SegmentationStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher&) {
  blobs_ = {};
  if (frame.image.empty()) return;
  try {
    blobs_ = segmenter_.Process(frame.image).blobs;
  } catch (const DataError& e) {
    status.faults.push_back(std::string("segmentation: ") + e.what());
  }
}

ThumbnailStage::ThumbnailStage(const ThumbnailOptions& options, const BlobView* blobs)
    : options_(options), blobs_(blobs) {
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
  if (blobs_ != nullptr) {
    for (const vision::Blob& b : blobs_->blobs()) {
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
  for (const pipeline::OdometrySample& s : frame.odometry) {
    // A sample that is not a number (refused by the tracker) adds nothing:
    // one NaN would make the distance NaN for the rest of the run.
    if (!std::isfinite(s.left_m_s) || !std::isfinite(s.right_m_s)) continue;
    if (last_utime_ >= 0) {
      status.distance_m +=
          0.5 * (s.left_m_s + s.right_m_s) * 1e-6 * static_cast<double>(s.utime - last_utime_);
    }
    last_utime_ = s.utime;
  }
  if (frame.odometry.empty()) return;
  const pipeline::OdometrySample& latest = frame.odometry.back();
  plantscale_odometry_t m{};
  m.utime = latest.utime;
  m.left_m_s = latest.left_m_s;
  m.right_m_s = latest.right_m_s;
  m.distance_m = status.distance_m;
  m.valid = std::isfinite(latest.left_m_s) && std::isfinite(latest.right_m_s) ? 1 : 0;
  publisher.Publish(channels::kOdometry, m);
}

void SimTruthStage::Process(const VehicleFrame& frame, RunStatus&, Publisher& publisher) {
  if (!frame.truth) return;
  publisher.Publish(channels::kSimTruth,
                    telemetry::TruthToLcm(frame.truth->grid, frame.utime, frame.frame_index));
  const sim::Pose2& p = frame.truth->pose;
  publisher.Publish(channels::kSimTruthPose,
                    ToLcm(telemetry::Pose{p.x_m, p.y_m, p.heading_rad, Eigen::Matrix3d::Zero()}, frame.utime));
}

PipelineStage::PipelineStage(const geometry::CameraModel& camera,
                             const pipeline::PipelineOptions& options, treatment::NozzleSink sink)
    : pipeline_(camera, options, std::move(sink)) {
  const auto n = static_cast<size_t>(options.treatment.scheduler.bar.nozzles);
  open_since_.assign(n, -1);
  open_sum_.assign(n, Eigen::Vector2d::Zero());
  open_ticks_.assign(n, 0);
}

void PipelineStage::PublishGrid(const pipeline::FrameResult& r, Publisher& publisher) {
  GridEstimate e;
  e.utime = r.utime;
  e.frame_index = r.frame_index;
  e.state = r.state;
  e.covariance = r.covariance;
  switch (r.mode) {
    case tracking::TrackerMode::kInitialising: e.mode = FilterMode::kInitialising; break;
    case tracking::TrackerMode::kLost: e.mode = FilterMode::kLost; break;
    case tracking::TrackerMode::kTracking:
      e.mode = r.report.updated ? FilterMode::kTracking : FilterMode::kDeadReckoning;
      break;
  }
  for (const tracking::Association& a : r.report.associations) {
    if (std::find(e.lines_in_view.begin(), e.lines_in_view.end(), a.m) == e.lines_in_view.end()) {
      e.lines_in_view.push_back(a.m);
    }
  }
  std::sort(e.lines_in_view.begin(), e.lines_in_view.end());
  e.observations = static_cast<int>(r.track_features.size());
  e.validated = r.report.matched;
  e.innovation_nis = r.report.nis;
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
  if (2 * r.learned_decided > r.observations) return plantscale_plant_t::WHY_LEARNED;
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

// The fail-safe state of the frame's last tick, and why the bar is closed
// (the tracker and the operator report their own states; before the first
// frame the bar is closed by design, not by a fault).
void PipelineStage::ReportTicks(RunStatus& status) {
  for (const treatment::TickResult& tick : ticks_) {
    last_tick_ = tick;
    ticked_ = true;
    RecordShots(tick);
  }
  if (!ticked_) return;
  status.failsafe = last_tick_.fail_reasons != 0;
  if (pipeline_.treatment()->last_frame_utime() < 0) return;
  for (const std::string& m : last_tick_.messages) {
    if (m.rfind("tracker", 0) != 0 && m.rfind("held", 0) != 0) {
      status.faults.push_back("treatment: bar closed: " + m);
    }
  }
}

void PipelineStage::ReportUncertainty(int64_t utime, Publisher& publisher) {
  const bool uncertain = ticked_ && (last_tick_.fail_reasons & treatment::kPositionUncertain) != 0;
  if (uncertain == uncertain_) return;
  uncertain_ = uncertain;
  plantscale_event_t e{};
  e.utime = utime;
  e.severity = uncertain ? plantscale_event_t::SEVERITY_WARNING : plantscale_event_t::SEVERITY_INFO;
  e.kind = "bar_uncertain";
  std::string why = "plant position uncertain";
  for (const std::string& m : last_tick_.messages) {
    if (m.rfind("plant position", 0) == 0) why = m;
  }
  e.text = uncertain ? "bar closed: " + why
                     : "plant position at the bar known again (95 % ellipse within the footprint's margin)";
  publisher.Publish(channels::kEvents, e);
}

void PipelineStage::RecordShots(const treatment::TickResult& tick) {
  std::vector<Eigen::Vector2d> centre(open_since_.size(), Eigen::Vector2d::Zero());
  for (const treatment::NozzleTarget& t : tick.opened) {
    centre[static_cast<size_t>(t.nozzle)] = {0.5 * (t.x0 + t.x1), 0.5 * (t.y0 + t.y1)};
  }
  for (size_t i = 0; i < open_since_.size(); ++i) {
    const bool open = (tick.open_mask >> i) & 1u;
    if (open) {
      if (open_since_[i] < 0) open_since_[i] = tick.utime, open_sum_[i].setZero(), open_ticks_[i] = 0;
      open_sum_[i] += centre[i];
      ++open_ticks_[i];
    } else if (open_since_[i] >= 0) {
      shots_.push_back({static_cast<int>(i), open_since_[i], tick.utime,
                        open_sum_[i] / std::max(1, open_ticks_[i]), -1});
      open_since_[i] = -1;
    }
  }
}

void PipelineStage::Process(const VehicleFrame& frame, RunStatus& status, Publisher& publisher) {
  const int8_t mode = status.commands.mode;
  std::optional<treatment::SprayMode> spray;
  if (mode != 0) {
    spray = mode == plantscale_command_t::MODE_SPRAY_WEED ? treatment::SprayMode::kWeed
                                                          : treatment::SprayMode::kCrop;
  }
  pipeline_.SetOperator(status.commands.held(), spray);
  if (!learned_reported_ && !pipeline_.learned_fault().empty()) {
    // Once, as an event; every heartbeat carries it as a fault line.
    Event(publisher, frame.utime, "segmenter_model_not_loaded", pipeline_.learned_fault());
  }
  learned_reported_ = true;
  ticks_.clear();
  const pipeline::FrameResult& r =
      pipeline_.Step(frame.utime, frame.frame_index, frame.image, frame.odometry, &ticks_);
  blobs_ = r.blobs;
  status.faults.insert(status.faults.end(), r.faults.begin(), r.faults.end());
  // Wheel slip this frame (a burst may begin and end between two frames).
  const tracking::SlipGuard& slip = pipeline_.tracker().slip_guard();
  if (slip.slipping() || slip.bursts() != slip_bursts_) {
    status.faults.push_back("odometry: wheel slip (burst " + std::to_string(slip.bursts()) +
                            "): dead reckoning with the ground speed from before it");
    slip_bursts_ = slip.bursts();
  }
  if (slip.faulty_wheel() != 0) {
    status.faults.push_back(std::string("odometry: ") +
                            (slip.faulty_wheel() == 1 ? "left" : "right") +
                            " wheel disagrees with the other (encoder stalled or wheel spinning "
                            "alone): read from the other wheel, turn rate held");
  }
  if (r.accepted) PublishGrid(r, publisher);
  if (r.report.row_spacing_mismatch) {
    // Once a run: the drill's spacing in the crop profile is not the bed's.
    Event(publisher, frame.utime, "row_spacing_mismatch", r.report.row_spacing_mismatch->Text());
  }
  if (!pipeline_.treatment()) return;
  ReportTicks(status);
  ReportUncertainty(frame.utime, publisher);
  if (r.treatment) {
    if (r.treatment->map_reset) next_tile_row_ = 0;
    last_frame_index_ = frame.frame_index;
    PublishPlants(frame, *r.treatment, publisher);
  }
  PublishNozzles(frame.utime, publisher);
  if (r.treatment) PublishTiles(frame.utime, publisher);
}

// Plants whose record changed since the last message, every 0.5 s of
// message time (the list is the largest channel: it must fit the budget),
// leaving out records seen only once (leaf fragments, noise).
void PipelineStage::PublishPlants(const VehicleFrame& frame, const treatment::FrameTreatment& t,
                                   Publisher& publisher) {
  if (t.map_reset) changed_plants_.clear();
  NoteNewlySprayed();
  if (!t.classified) return;
  changed_plants_.insert(changed_plants_.end(), t.plant_ids.begin(), t.plant_ids.end());
  if (last_plants_utime_ >= 0 && frame.utime - last_plants_utime_ < kPlantListPeriodUs) return;
  std::vector<PlantObservation> plants;
  for (int id : TakeChangedPlants()) {
    if (id < 0) continue;
    const treatment::PlantRecord* r = system().registry().Find(id);
    if (r != nullptr && r->confirmed()) plants.push_back(Observation(*r, WhyCode(*r)));
  }
  last_plants_utime_ = frame.utime;
  publisher.Publish(channels::kPlants, ToLcm(plants, frame.utime, frame.frame_index));
}

void PipelineStage::PublishNozzles(int64_t utime, Publisher& publisher) {
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

// The run's end: the records in the last view judged on the frames they
// had (TreatmentSystem::FlushRecordsInView), the plant records changed
// since the last list, and every plant the mode would spray that the bar
// had not yet reached, so that the station, log and report tell them from
// misses; then the last tile rows.
void PipelineStage::Finish(int64_t utime, Publisher& publisher) {
  const double bar_y = BarY();
  const bool spray_crop = system().options().scheduler.mode == treatment::SprayMode::kCrop;
  NoteNewlySprayed();
  const std::vector<int> judged = pipeline_.treatment()->FlushRecordsInView();
  changed_plants_.insert(changed_plants_.end(), judged.begin(), judged.end());
  const std::vector<int> ids = TakeChangedPlants();
  std::vector<PlantObservation> plants;
  const std::vector<treatment::PlantRecord>& records = system().registry().records();
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

void PipelineStage::NoteNewlySprayed() {
  const std::vector<int> sprayed = pipeline_.treatment()->TakeNewlySprayed();
  changed_plants_.insert(changed_plants_.end(), sprayed.begin(), sprayed.end());
}

std::vector<int> PipelineStage::TakeChangedPlants() {
  std::vector<int> ids = std::move(changed_plants_);
  changed_plants_.clear();
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

double PipelineStage::BarY() const {
  return pipeline_.tracker().forward_distance_m() - system().options().scheduler.bar.bar_offset_m;
}

bool PipelineStage::TileRowObserved(int tile_row) const {
  const treatment::TreatmentMap& map = system().map();
  for (int r = tile_row * kTileCells; r < std::min(map.rows(), (tile_row + 1) * kTileCells); ++r) {
    for (int c = 0; c < map.columns(); ++c) {
      if (map.Observed(c, r)) return true;
    }
  }
  return false;
}

// A tile row is sent once the bar has passed it: its cells are final. At
// the end of the run, every row up to the last the camera saw.
void PipelineStage::PublishTiles(int64_t utime, Publisher& publisher, bool to_the_end) {
  if (!to_the_end && pipeline_.tracker().mode() != tracking::TrackerMode::kTracking) return;
  const treatment::TreatmentMap& map = system().map();
  const double bar_y = BarY();
  const double edge = kTileCells * map.options().cell_m;
  const int last_seen = to_the_end ? LastObservedTileRow() : -1;
  // A tile row is due once the bar has passed it (at the end of the run:
  // up to the last row the camera saw).
  const auto due = [&](int row) {
    if ((row + 1) * kTileCells > map.rows()) return false;
    return to_the_end ? row <= last_seen : map.options().start_y_m + (row + 1) * edge < bar_y;
  };
  for (; due(next_tile_row_); ++next_tile_row_) {
    for (int tx = 0; tx * kTileCells < map.columns(); ++tx) {
      publisher.Publish(channels::kMapTiles, ToLcm(Tile(tx, next_tile_row_), utime));
    }
  }
  ++tile_revision_;
}

// The last tile row (from next_tile_row_ on) with a cell the camera saw; −1: none.
int PipelineStage::LastObservedTileRow() const {
  for (int row = system().map().rows() / kTileCells - 1; row >= next_tile_row_; --row) {
    if (TileRowObserved(row)) return row;
  }
  return -1;
}

// One kTileCells² tile of the treatment map: treated, else the cell's class,
// unknown where the camera never saw soil or beyond the map's columns.
MapTileDelta PipelineStage::Tile(int tx, int ty) const {
  const treatment::TreatmentMap& map = system().map();
  const double edge = kTileCells * map.options().cell_m;
  MapTileDelta d;
  d.tile_x = tx;
  d.tile_y = ty;
  d.revision = tile_revision_;
  d.origin_m = {map.origin_x_m() + tx * edge, map.options().start_y_m + ty * edge};
  d.resolution_m = map.options().cell_m;
  d.width = d.height = kTileCells;
  d.cells.reserve(static_cast<size_t>(kTileCells * kTileCells));
  for (int j = 0; j < kTileCells; ++j) {
    for (int i = 0; i < kTileCells; ++i) {
      const int c = tx * kTileCells + i;
      const int r = ty * kTileCells + j;
      const treatment::CellClass cls = c < map.columns() ? map.ClassOf(c, r) : treatment::CellClass::kSoil;
      d.cells.push_back(c >= map.columns() ? plantscale_map_tile_t::CELL_UNKNOWN
                        : map.Treated(c, r) ? plantscale_map_tile_t::CELL_TREATED
                        : cls == treatment::CellClass::kSoil && !map.Observed(c, r)
                            ? plantscale_map_tile_t::CELL_UNKNOWN
                            : TileCell(cls));
    }
  }
  return d;
}

}  // namespace plantscale::vehicle
