#include "review/synthetic_run.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "engine/geometry/camera_model.h"
#include "telemetry/channels.h"
#include "telemetry/codec.h"
#include "telemetry/convert.h"
#include "telemetry/subscriber.h"

namespace plantscale::review {
namespace {

namespace tm = plantscale::telemetry;
namespace ch = plantscale::telemetry::channels;

struct FieldPlant {
  int64_t id;
  tm::PlantKind kind;
  Eigen::Vector2d position;
};

class Generator {
 public:
  explicit Generator(const SyntheticRunOptions& o) : o_(o), rng_(o.seed), camera_({}) {
    PlantField();
  }
  std::vector<tm::LogEvent> Run();

 private:
  void PlantField();
  tm::Pose PoseAt(double y) const;
  template <typename M>
  void Emit(const std::string& channel, M m, int64_t utime) {
    m.seq = seq_[channel]++;
    const tm::Bytes b = tm::Encode(m);
    events_.push_back({static_cast<int64_t>(events_.size()), utime, channel, b});
  }
  void Frame(int frame, double t, int64_t utime);
  void Grid(int frame, const tm::Pose& p, double t, int64_t utime);
  void Plants(int frame, const tm::Pose& p, int64_t utime);
  void Nozzles(const tm::Pose& p, double prev_y, int64_t utime);
  void Tiles(const tm::Pose& p, int64_t utime, bool flush);
  void Thumbnail(int frame, const tm::Pose& p, int64_t utime);
  uint8_t CellAt(const Eigen::Vector2d& f) const;
  // The plants with y in [y0, y1], in the order of plants_ (so that the
  // random draws per plant are those of a pass over every plant): the run's
  // cost stays linear in its length.
  std::vector<const FieldPlant*> Between(double y0, double y1) const;

  SyntheticRunOptions o_;
  std::mt19937 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  geometry::CameraModel camera_;
  std::vector<FieldPlant> plants_;
  std::vector<std::pair<double, size_t>> by_y_;  // (y, index into plants_), sorted
  std::map<std::string, int64_t> seq_;
  std::vector<tm::LogEvent> events_;
  int next_tile_row_ = 0;
  int64_t boot_ = 0;
  bool restarted_ = false, nan_sent_ = false;
};

void Generator::PlantField() {
  int64_t id = 0;
  int line = 0;
  for (double y = 0.5; y < o_.length_m + 3.0; y += o_.plant_spacing_m, ++line) {
    for (int n = -1; n <= 1; ++n) {
      const int64_t plant_id = id++;  // ids as without missing plants
      if (std::find(o_.missing_crops.begin(), o_.missing_crops.end(), std::make_pair(n, line)) !=
          o_.missing_crops.end()) {
        continue;
      }
      plants_.push_back({plant_id, tm::PlantKind::kCrop, {n * o_.row_spacing_m, y}});
    }
  }
  std::uniform_real_distribution<double> ux(-0.7, 0.7), uy(0.3, o_.length_m + 3.0);
  const int weeds = static_cast<int>(o_.weeds_per_m * (o_.length_m + 3.0));
  for (int i = 0; i < weeds; ++i) plants_.push_back({id++, tm::PlantKind::kWeed, {ux(rng_), uy(rng_)}});
  for (size_t i = 0; i < plants_.size(); ++i) by_y_.emplace_back(plants_[i].position.y(), i);
  std::sort(by_y_.begin(), by_y_.end());
}

std::vector<const FieldPlant*> Generator::Between(double y0, double y1) const {
  std::vector<size_t> index;
  for (auto it = std::lower_bound(by_y_.begin(), by_y_.end(), std::make_pair(y0, size_t{0}));
       it != by_y_.end() && it->first <= y1; ++it) {
    index.push_back(it->second);
  }
  std::sort(index.begin(), index.end());
  std::vector<const FieldPlant*> out;
  for (size_t i : index) out.push_back(&plants_[i]);
  return out;
}

tm::Pose Generator::PoseAt(double y) const {
  const double w = 2.0 * std::numbers::pi / o_.zigzag_period_m;
  tm::Pose p;
  p.y_m = y;
  p.x_m = o_.zigzag_amplitude_m * std::sin(w * y);
  p.heading_rad = -std::atan(o_.zigzag_amplitude_m * w * std::cos(w * y));  // CCW from +y
  return p;
}

Eigen::Vector2d ToVehicle(const tm::Pose& p, const Eigen::Vector2d& f) {
  const double c = std::cos(p.heading_rad), s = std::sin(p.heading_rad);
  const Eigen::Vector2d d = f - Eigen::Vector2d(p.x_m, p.y_m);
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
}

std::vector<tm::LogEvent> Generator::Run() {
  boot_ = o_.start_utime;
  plantscale_event_t start{};
  start.severity = plantscale_event_t::SEVERITY_INFO;
  start.kind = "run_started";
  start.text = "synthetic run started";
  Emit(ch::kEvents, start, o_.start_utime);
  const int frames = static_cast<int>(o_.length_m / o_.speed_m_s * o_.frame_rate_hz);
  for (int f = 0; f <= frames; ++f) {
    const double t = f / o_.frame_rate_hz;
    Frame(f, t, o_.start_utime + static_cast<int64_t>(t * 1e6));
  }
  // As the vehicle's runner ends a run.
  plantscale_event_t end{};
  end.utime = o_.start_utime + static_cast<int64_t>(frames / o_.frame_rate_hz * 1e6);
  end.severity = plantscale_event_t::SEVERITY_INFO;
  end.kind = "run_finished";
  end.text = "run finished after " + std::to_string(frames + 1) + " frames";
  Emit(ch::kEvents, end, end.utime);
  return std::move(events_);
}

void Generator::Frame(int frame, double t, int64_t utime) {
  const double y = o_.speed_m_s * t, prev_y = o_.speed_m_s * std::max(0.0, t - 1.0 / o_.frame_rate_hz);
  tm::Pose p = PoseAt(y);
  const double sigma = 0.01 + 0.01 * std::fmod(t, 4.0);  // dead reckoning grows, fixes reset it
  p.covariance.diagonal() << sigma * sigma, (1.5 * sigma) * (1.5 * sigma), 1e-4;
  plantscale_odometry_t odo{};
  odo.left_m_s = odo.right_m_s = o_.speed_m_s;
  odo.distance_m = y;
  odo.valid = 1;
  Emit(ch::kOdometry, odo, utime);
  Emit(ch::kPose, tm::ToLcm(p, utime), utime);
  Emit(ch::kSimTruthPose, tm::ToLcm(PoseAt(y), utime), utime);
  Grid(frame, p, t, utime);
  Plants(frame, p, utime);
  Nozzles(p, prev_y, utime);
  Tiles(p, utime, false);
  const int per_half_second = static_cast<int>(std::lround(o_.frame_rate_hz / 2.0));
  if (frame % per_half_second == 0) Thumbnail(frame, p, utime);
  if (o_.restart_at_s && !restarted_ && t >= *o_.restart_at_s) {
    restarted_ = true;
    boot_ = utime;
    seq_.clear();
  }
  const bool heartbeat = !o_.heartbeat_stops_at_s || t < *o_.heartbeat_stops_at_s;
  if (frame % per_half_second == 0 && heartbeat) {
    tm::Health h;
    h.source = "synthetic";
    h.boot_utime = boot_;
    h.frame_rate_hz = o_.frame_rate_hz;
    h.frames = frame + 1;
    h.distance_m = y;
    h.failsafe = false;
    Emit(ch::kHealth, tm::ToLcm(h, utime), utime);
  }
  if (std::abs(y - 0.5 * o_.length_m) < 0.5 * o_.speed_m_s / o_.frame_rate_hz) {
    plantscale_event_t e{};
    e.utime = utime;
    e.severity = plantscale_event_t::SEVERITY_WARNING;
    e.kind = "frame_dropped";
    e.text = "camera frame dropped (synthetic)";
    Emit(ch::kEvents, e, utime);
  }
}

void Generator::Grid(int frame, const tm::Pose& p, double t, int64_t utime) {
  const double c = std::cos(p.heading_rad), s = std::sin(p.heading_rad);
  double y0 = 0.5;
  while (y0 < p.y_m + 0.45) y0 += o_.plant_spacing_m;  // first line above the image's bottom edge
  geometry::GridState truth;
  truth.offset_m = -p.x_m / c;
  truth.forward_m = (y0 - p.y_m) + p.x_m * s / c;
  truth.bearing_rad = p.heading_rad;
  truth.row_spacing_m = o_.row_spacing_m;
  truth.plant_spacing_m = o_.plant_spacing_m;
  Emit(ch::kSimTruth, tm::TruthToLcm(truth, utime, frame), utime);
  tm::GridEstimate e;
  e.utime = utime;
  e.frame_index = frame;
  e.state = truth;
  const double sd[5] = {0.008, 0.015, 0.006, 0.004, 0.004};
  e.state.offset_m += sd[0] * noise_(rng_);
  e.state.forward_m += sd[1] * noise_(rng_);
  e.state.bearing_rad += sd[2] * noise_(rng_);
  for (int i = 0; i < 5; ++i) e.covariance(i, i) = sd[i] * sd[i];
  e.mode = t < 1.0 ? tm::FilterMode::kInitialising : tm::FilterMode::kTracking;
  e.observations = 9;
  e.validated = 8;
  plantscale_grid_state_t m = tm::ToLcm(e);
  if (o_.nan_grid_at_s && !nan_sent_ && t >= *o_.nan_grid_at_s) {
    nan_sent_ = true;
    m.state[0] = std::numeric_limits<double>::quiet_NaN();
  }
  Emit(ch::kGrid, m, utime);
}

void Generator::Plants(int frame, const tm::Pose& p, int64_t utime) {
  std::vector<tm::PlantObservation> seen;
  for (const FieldPlant* fp : Between(p.y_m - 0.5, p.y_m + 3.5)) {
    const FieldPlant& f = *fp;
    const Eigen::Vector2d v = ToVehicle(p, f.position);
    if (v.y() < 0.9 || v.y() > 2.3 || std::abs(v.x()) > 0.8) continue;
    tm::PlantObservation o;
    o.id = f.id;
    o.kind = f.kind;
    o.position_m = f.position + 0.01 * Eigen::Vector2d(noise_(rng_), noise_(rng_));
    o.covariance = Eigen::Vector2d(2.0e-4, 1.0e-4).asDiagonal();
    o.size_m2 = f.kind == tm::PlantKind::kCrop ? 0.01 : 0.002;
    o.sprayed = f.kind == tm::PlantKind::kWeed;
    o.why = f.kind == tm::PlantKind::kWeed ? plantscale_plant_t::WHY_OUTSIDE_REGION
                                           : plantscale_plant_t::WHY_CROP_IN_REGION;
    seen.push_back(o);
  }
  Emit(ch::kPlants, tm::ToLcm(seen, utime, frame), utime);
}

void Generator::Nozzles(const tm::Pose& p, double prev_y, int64_t utime) {
  tm::NozzleBar bar;
  bar.open.assign(static_cast<size_t>(o_.nozzles), false);
  bar.fault.assign(static_cast<size_t>(o_.nozzles), 0);
  bar.failsafe = false;
  const double width = 1.5 / o_.nozzles;
  for (const FieldPlant* fp : Between(prev_y, p.y_m)) {
    const FieldPlant& f = *fp;
    if (f.kind != tm::PlantKind::kWeed || f.position.y() <= prev_y || f.position.y() > p.y_m) continue;
    const int n = std::clamp(static_cast<int>((f.position.x() + 0.75) / width), 0, o_.nozzles - 1);
    bar.open[static_cast<size_t>(n)] = true;
    bar.shots.push_back({n, utime, utime + 80'000, f.position, f.id});
  }
  Emit(ch::kNozzles, tm::ToLcm(bar, utime), utime);
}

uint8_t Generator::CellAt(const Eigen::Vector2d& f) const {
  uint8_t cell = plantscale_map_tile_t::CELL_SOIL;
  for (const FieldPlant* pp : Between(f.y() - 0.1, f.y() + 0.1)) {
    const FieldPlant& p = *pp;
    if (std::abs(p.position.y() - f.y()) > 0.1) continue;
    const double d = (p.position - f).norm();
    if (p.kind == tm::PlantKind::kCrop && d < 0.06) cell = plantscale_map_tile_t::CELL_CROP;
    if (p.kind == tm::PlantKind::kWeed && d < 0.05) return d < 0.025 ? plantscale_map_tile_t::CELL_WEED
                                                                      : plantscale_map_tile_t::CELL_TREATED;
  }
  return cell;
}

// A tile row is sent once the vehicle is map_lag_m past its end.
void Generator::Tiles(const tm::Pose& p, int64_t utime, bool) {
  const double edge = o_.tile_cells * o_.cell_m;
  while ((next_tile_row_ + 1) * edge < p.y_m - o_.map_lag_m) {
    for (int tx = -1; tx <= 0; ++tx) {
      tm::MapTileDelta t;
      t.tile_x = tx, t.tile_y = next_tile_row_, t.revision = 0;
      t.origin_m = {tx * edge, next_tile_row_ * edge};
      t.resolution_m = o_.cell_m;
      t.width = t.height = o_.tile_cells;
      t.cells.resize(static_cast<size_t>(t.width * t.height));
      for (int j = 0; j < t.height; ++j) {
        for (int i = 0; i < t.width; ++i) {
          const Eigen::Vector2d f = t.origin_m + o_.cell_m * Eigen::Vector2d(i + 0.5, j + 0.5);
          t.cells[static_cast<size_t>(j * t.width + i)] =
              std::abs(f.x()) < 0.8 ? CellAt(f) : plantscale_map_tile_t::CELL_UNKNOWN;
        }
      }
      Emit(ch::kMapTiles, tm::ToLcm(t, utime), utime);
    }
    ++next_tile_row_;
  }
}

void Generator::Thumbnail(int frame, const tm::Pose& p, int64_t utime) {
  const double scale = 0.25;
  cv::Mat img(120, 160, CV_8UC3, cv::Scalar(70, 105, 140));
  plantscale_thumbnail_t m{};
  m.utime = utime;
  m.frame_index = frame;
  m.source_width = static_cast<int16_t>(camera_.width());
  m.source_height = static_cast<int16_t>(camera_.height());
  m.width = 160, m.height = 120;
  for (const FieldPlant* fp : Between(p.y_m - 1.0, p.y_m + 5.5)) {
    const FieldPlant& f = *fp;
    const Eigen::Vector2d v = ToVehicle(p, f.position);
    if (v.y() < 0.3 || v.y() > 4.0) continue;
    const auto uv = camera_.Project({v.x(), v.y(), 0.0});
    if (!uv || uv->x() < 0 || uv->y() < 0 || uv->x() >= camera_.width() || uv->y() >= camera_.height()) continue;
    const bool crop = f.kind == tm::PlantKind::kCrop;
    const int r = crop ? 4 : 2;
    cv::circle(img, cv::Point(static_cast<int>(uv->x() * scale), static_cast<int>(uv->y() * scale)), r,
               crop ? cv::Scalar(40, 170, 60) : cv::Scalar(60, 200, 120), cv::FILLED);
    plantscale_blob_t b{};
    b.u = static_cast<float>(uv->x()), b.v = static_cast<float>(uv->y());
    b.area_px = crop ? 250 : 60;
    b.cls = crop ? 1 : 2;
    m.blobs.push_back(b);
  }
  cv::imencode(".jpg", img, m.jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
  m.jpeg_size = static_cast<int32_t>(m.jpeg.size());
  m.num_blobs = static_cast<int32_t>(m.blobs.size());
  Emit(ch::kThumbnail, m, utime);
}

}  // namespace

std::vector<tm::LogEvent> SyntheticRun(const SyntheticRunOptions& options) {
  return Generator(options).Run();
}

void WriteSyntheticLog(const std::filesystem::path& path, const SyntheticRunOptions& options) {
  tm::LogWriter log(path);
  for (const tm::LogEvent& e : SyntheticRun(options)) {
    log.Write(e.channel, e.data.data(), e.data.size(), e.utime);
  }
}

}  // namespace plantscale::review
