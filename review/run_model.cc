#include "review/run_model.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <sstream>

#include "telemetry/channels.h"
#include "telemetry/convert.h"

namespace plantscale::review {
namespace {

namespace tm = plantscale::telemetry;

std::string Fixed(double value, int decimals) {
  std::ostringstream out;
  out.precision(decimals);
  out << std::fixed << value;
  return out.str();
}

std::string Seconds(double s) { return Fixed(s, 1) + " s"; }

bool Contains(const std::vector<std::string>& v, const std::string& s) {
  for (const std::string& x : v) {
    if (x == s) return true;
  }
  return false;
}

// RMS of estimate − truth over the frames (utime) both traces have.
std::optional<double> RmsOffsetError(const std::vector<TraceSample>& estimate,
                                     const std::vector<TraceSample>& truth) {
  std::map<int64_t, double> truth_at;
  for (const TraceSample& t : truth) truth_at[t.utime] = t.offset_m;
  double sum2 = 0.0;
  int n = 0;
  for (const TraceSample& e : estimate) {
    const auto it = truth_at.find(e.utime);
    if (it == truth_at.end()) continue;
    sum2 += (e.offset_m - it->second) * (e.offset_m - it->second);
    ++n;
  }
  if (n == 0) return std::nullopt;
  return std::sqrt(sum2 / n);
}

}  // namespace

OptionErrors RunModelOptions::Validate() const {
  OptionErrors errors;
  RequirePositive(errors, "link_lost_after_s", link_lost_after_s);
  RequireNonNegative(errors, "max_event_snapshots", max_event_snapshots);
  return errors;
}

double EllipseScale2d(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("ellipse confidence must be in (0, 1)");
  }
  return -2.0 * std::log(1.0 - confidence);
}

RunModel::RunModel(const RunModelOptions& options) : options_(options) {
  ThrowIfInvalid("run model options", options_.Validate());
}

void RunModel::Follow(tm::Subscriber& subscriber) {
  subscriber.SetObserver([this](const std::string& channel, bool applied,
                                const tm::TelemetrySnapshot& state) {
    Observe(channel, applied, state);
  });
}

void RunModel::Observe(const std::string& channel, bool applied, const tm::TelemetrySnapshot& s) {
  using namespace tm::channels;
  ++messages_;
  subscriber_problems_ = s.problems;
  channels_ = s.channels;
  unknown_messages_ = s.unknown_channel_messages;
  const auto stats = s.channels.find(channel);
  if (stats != s.channels.end()) {
    last_message_utime_ = stats->second.last_recv_utime;
    if (first_message_utime_ == 0) first_message_utime_ = last_message_utime_;
  }
  if (!applied) return;
  if (channel == kGrid && s.grid) {
    ObserveGrid(*s.grid, trace_), grid_ = s.grid;
    if (stats != s.channels.end()) {
      grid_lag_ms_.push_back(static_cast<float>(1e-3 * static_cast<double>(stats->second.last_recv_utime - s.grid->utime)));
    }
  }
  if (channel == kSimTruth && s.truth) ObserveGrid(*s.truth, truth_trace_), truth_ = s.truth;
  if (channel == kPose || channel == kSimTruthPose) ObservePose(s);
  if (channel == kPlants) ObservePlants(s);
  if (channel == kMapTiles) ObserveTiles(s);
  if (channel == kHealth) ObserveHealth(s);
  if (channel == kEvents) ObserveEvent(s);
  if (channel == kThumbnail) thumbnail_ = s.thumbnail;
  if (channel == kOdometry && s.odometry) {
    distance_m_ = std::max(distance_m_, s.odometry->distance_m);
    if (odometry_history_.empty() || s.odometry->utime > odometry_history_.back().first) {
      odometry_history_.emplace_back(s.odometry->utime, distance_m_);
      if (odometry_history_.size() > kOdometryHistory) odometry_history_.pop_front();
    }
    speed_m_s_ = 0.5 * (s.odometry->left_m_s + s.odometry->right_m_s);
  }
  if (channel == kNozzles && s.nozzles) {
    nozzles_ = s.nozzles;
    shots_.insert(shots_.end(), s.nozzles->shots.begin(), s.nozzles->shots.end());
  }
}

double RunModel::DistanceAt(int64_t utime) const {
  if (utime <= 0 || odometry_history_.empty() || utime >= odometry_history_.back().first) {
    return distance_m_;
  }
  const auto after = std::lower_bound(
      odometry_history_.begin(), odometry_history_.end(), utime,
      [](const std::pair<int64_t, double>& h, int64_t t) { return h.first < t; });
  if (after == odometry_history_.begin()) return after->second;
  const auto before = std::prev(after);
  const double f = static_cast<double>(utime - before->first) /
                   static_cast<double>(after->first - before->first);
  return before->second + f * (after->second - before->second);
}

void RunModel::ObserveGrid(const tm::GridEstimate& g, std::vector<TraceSample>& trace) {
  TraceSample t;
  t.utime = g.utime;
  t.distance_m = DistanceAt(g.utime);
  t.offset_m = g.state.offset_m;
  t.offset_sigma_m = std::sqrt(std::max(0.0, g.covariance(0, 0)));
  t.bearing_rad = g.state.bearing_rad;
  t.bearing_sigma_rad = std::sqrt(std::max(0.0, g.covariance(2, 2)));
  t.mode = g.mode;
  trace.push_back(t);
}

void RunModel::ObservePose(const tm::TelemetrySnapshot& s) {
  pose_ = s.pose;
  truth_pose_ = s.truth_pose;
  const std::optional<tm::Pose> p = pose();
  if (p) path_.emplace_back(p->x_m, p->y_m);
}

void RunModel::ObservePlants(const tm::TelemetrySnapshot& s) {
  plants_ = s.plants;
  ++plant_messages_;
  const int64_t now = s.channels.at(tm::channels::kPlants).last_recv_utime;
  for (const tm::PlantObservation& p : s.plants) {
    PlantRecord& r = registry_[p.id];
    if (r.observations == 0) r.first_utime = now;
    r.plant = p;
    r.last_utime = now;
    ++r.observations;
  }
}

void RunModel::Feed(tm::Subscriber& subscriber, const std::string& channel, const void* data, size_t size,
                    int64_t recv_utime) {
  tile_hint_.reset();
  if (channel == tm::channels::kMapTiles) {
    plantscale_map_tile_t m;
    if (m.decode(data, 0, static_cast<int>(size)) >= 0) tile_hint_ = std::make_pair(m.tile_x, m.tile_y);
  }
  subscriber.Feed(channel, data, size, recv_utime);
  tile_hint_.reset();
}

void RunModel::ObserveTiles(const tm::TelemetrySnapshot& s) {
  if (tile_hint_) {
    const auto in = s.tiles.find(*tile_hint_);
    if (in == s.tiles.end()) return;
    const auto it = tiles_.find(*tile_hint_);
    if (it != tiles_.end() && it->second.revision >= in->second.revision) return;  // the newest wins
    tile_revisions_ += in->second.revision + 1 - (it != tiles_.end() ? it->second.revision + 1 : 0);
    tiles_[*tile_hint_] = in->second;
    NoteMapFront(in->second);
    return;
  }
  int sum = 0;
  for (const auto& [key, tile] : s.tiles) {
    sum += tile.revision + 1;
    NoteMapFront(tile);
    auto it = tiles_.find(key);
    if (it == tiles_.end() || it->second.revision != tile.revision) tiles_[key] = tile;
  }
  tile_revisions_ = sum;
}

void RunModel::NoteMapFront(const tm::MapTileDelta& tile) {
  const double end = tile.origin_m.y() + tile.height * tile.resolution_m;
  map_front_y_m_ = std::max(map_front_y_m_.value_or(end), end);
}

void RunModel::InsertPlant(const PlantRecord& record) {
  registry_[record.plant.id] = record;
  inserted_plants_ = true;
  ++plant_messages_;
  ++messages_;
}

void RunModel::ObserveHealth(const tm::TelemetrySnapshot& s) {
  if (!s.health) return;
  if (health_ && s.health->boot_utime != health_->boot_utime) {
    restarts_.push_back("vehicle process restarted (new boot time) after " +
                        Fixed(health_->distance_m, 1) + " m");
  }
  health_ = s.health;
  health_recv_utime_ = s.health_recv_utime;
  distance_m_ = std::max(distance_m_, s.health->distance_m);
  for (const std::string& f : s.health->faults) {
    if (!Contains(vehicle_faults_, f)) vehicle_faults_.push_back(f);
  }
}

void RunModel::ObserveEvent(const tm::TelemetrySnapshot& s) {
  if (s.events.empty()) return;
  const plantscale_event_t& e = s.events.back();
  events_.push_back(e);
  if (e.kind == "run_finished") finished_ = e;
  if (e.kind == "run_started") finished_.reset();
  if (e.severity >= plantscale_event_t::SEVERITY_WARNING &&
      static_cast<int>(event_snapshots_.size()) < options_.max_event_snapshots) {
    event_snapshots_.push_back({e, thumbnail_, grid_ ? grid_ : truth_});
  }
}

std::optional<tm::Pose> RunModel::pose() const { return pose_ ? pose_ : truth_pose_; }

LinkStatus RunModel::Link(int64_t now_utime) const {
  LinkStatus link;
  link.heartbeat_age_s = std::numeric_limits<double>::quiet_NaN();
  if (!health_ && inserted_plants_) {
    link.level = LinkLevel::kFinished;
    link.text = "an exported map: its plants only, no vehicle link";
    return link;
  }
  if (!health_) {
    link.level = messages_ == 0 ? LinkLevel::kNoMessages : LinkLevel::kLost;
    link.text = messages_ == 0 ? "NO MESSAGES: nothing received yet"
                               : "LINK LOST: no heartbeat (PLANTSCALE_HEALTH) received";
    return link;
  }
  link.heartbeat_age_s = 1e-6 * static_cast<double>(now_utime - health_recv_utime_);
  const bool lost = link.heartbeat_age_s > options_.link_lost_after_s;
  // The vehicle said the run is over: the link's quiet from then on is the
  // run's end, and a log replayed to its end (where time stops with the last
  // message, so the heartbeat never ages) says so too.
  if (finished_) {
    link.level = LinkLevel::kFinished;
    link.text = finished_->text + "; last heartbeat " + Seconds(link.heartbeat_age_s) + " ago";
    return link;
  }
  link.level = lost ? LinkLevel::kLost : LinkLevel::kOk;
  link.text = lost ? "LINK LOST: no heartbeat for " + Seconds(link.heartbeat_age_s)
                   : "link ok, heartbeat " + Seconds(link.heartbeat_age_s) + " ago";
  return link;
}

std::vector<std::string> RunModel::Problems(int64_t now_utime) const {
  std::vector<std::string> out;
  const LinkStatus link = Link(now_utime);
  if (link.level != LinkLevel::kOk && link.level != LinkLevel::kFinished) out.push_back(link.text);
  const int64_t known = messages_ - unknown_messages_;
  if (messages_ > 0 && known == 0) {
    out.push_back("no plantscale messages: " + std::to_string(messages_) +
                  " messages on other channels (a log from another program?)");
  }
  out.insert(out.end(), restarts_.begin(), restarts_.end());
  for (const std::string& f : vehicle_faults_) out.push_back("vehicle fault: " + f);
  out.insert(out.end(), subscriber_problems_.begin(), subscriber_problems_.end());
  return out;
}

RunSummary RunModel::Summary() const {
  RunSummary s;
  s.distance_m = distance_m_;
  const std::vector<TraceSample>& trace = !trace_.empty() ? trace_ : truth_trace_;
  s.offset_source = !trace_.empty() ? "tracker" : !truth_trace_.empty() ? "simulator truth" : "none";
  double sum = 0.0, sum2 = 0.0;
  for (const TraceSample& t : trace) sum += t.offset_m, sum2 += t.offset_m * t.offset_m;
  if (!trace.empty()) {
    const double n = static_cast<double>(trace.size());
    s.mean_offset_m = sum / n;
    s.rms_offset_m = std::sqrt(sum2 / n);
  }
  s.rms_offset_error_m = RmsOffsetError(trace_, truth_trace_);
  for (const auto& [id, r] : registry_) {
    const bool crop = r.plant.kind == tm::PlantKind::kCrop;
    const bool weed = r.plant.kind == tm::PlantKind::kWeed;
    s.crop_seen += crop;
    s.weeds_seen += weed;
    s.crop_treated += crop && r.plant.sprayed;
    s.weeds_treated += weed && r.plant.sprayed;
    const bool not_reached = !r.plant.sprayed && r.plant.why == plantscale_plant_t::WHY_NOT_REACHED;
    s.crop_not_reached += crop && not_reached;
    s.weeds_not_reached += weed && not_reached;
  }
  s.weeds_left = s.weeds_seen - s.weeds_treated - s.weeds_not_reached;
  s.plants_seen = static_cast<int>(registry_.size());
  s.shots = static_cast<int>(shots_.size());
  if (!tiles_.empty()) {
    double area = 0.0;
    for (const auto& [key, t] : tiles_) {
      for (uint8_t c : t.cells) {
        if (c == plantscale_map_tile_t::CELL_TREATED) area += t.resolution_m * t.resolution_m;
      }
    }
    s.area_treated_m2 = area;
  }
  for (const std::string& f : vehicle_faults_) s.faults.push_back("vehicle: " + f);
  for (const plantscale_event_t& e : events_) {
    if (e.severity >= plantscale_event_t::SEVERITY_ERROR) s.faults.push_back("event: " + e.text);
  }
  for (const auto& [name, c] : channels_) {
    if (c.decode_failures + c.invalid > 0) {
      s.faults.push_back(name + ": " + std::to_string(c.decode_failures + c.invalid) +
                         " bad messages");
    }
  }
  s.faults.insert(s.faults.end(), restarts_.begin(), restarts_.end());
  s.messages = messages_;
  s.vehicle_restarts = static_cast<int>(restarts_.size());
  return s;
}

}  // namespace plantscale::review
