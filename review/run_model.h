#pragma once
// What the station and the report show, accumulated from the subscriber
// message by message (Subscriber::SetObserver): the latest state of every
// channel plus the whole run's offset trace, plant registry, shots, path,
// map tiles and events, and a plain-words list of what is wrong (no
// messages, lost link, vehicle restarts, bad messages, foreign channels).
// No VTK here: the scene pieces read this.

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/common/options.h"
#include "telemetry/subscriber.h"

namespace plantscale::review {

struct RunModelOptions {
  double link_lost_after_s = 2.0;  // heartbeat age that counts as a lost link (2 Hz heartbeat)
  int max_event_snapshots = 6;     // thumbnails kept at warning/error events

  OptionErrors Validate() const;
};

// One filter state against distance driven (the offset trace).
struct TraceSample {
  int64_t utime = 0;
  double distance_m = 0.0;
  double offset_m = 0.0;
  double offset_sigma_m = 0.0;
  double bearing_rad = 0.0;
  double bearing_sigma_rad = 0.0;
  telemetry::FilterMode mode = telemetry::FilterMode::kInitialising;
};

struct PlantRecord {
  telemetry::PlantObservation plant;  // newest observation of this id
  // From an exported map (RunModel::InsertPlant): the decision's reason in
  // its words (plant.why unused), and no distance to the predicted crop.
  std::string why_text;
  int64_t first_utime = 0;
  int64_t last_utime = 0;
  int observations = 0;
};

struct EventSnapshot {
  plantscale_event_t event;
  std::optional<plantscale_thumbnail_t> thumbnail;  // latest at the event
  std::optional<telemetry::GridEstimate> grid;
};

// kFinished: the heartbeat stopped after the vehicle said the run finished
// (a run_finished event and no run_started since): quiet, not lost.
enum class LinkLevel { kNoMessages, kOk, kLost, kFinished };

struct LinkStatus {
  LinkLevel level = LinkLevel::kNoMessages;
  double heartbeat_age_s = 0.0;  // NaN when no heartbeat was ever seen
  std::string text;              // for people: "link ok", "LINK LOST: no heartbeat for 3.1 s"
};

struct RunSummary {
  double distance_m = 0.0;
  std::string offset_source;  // "tracker", "simulator truth" or "none"
  double mean_offset_m = 0.0;
  double rms_offset_m = 0.0;
  // Tracker offset minus the simulator's truth at the same frame, when both are logged.
  std::optional<double> rms_offset_error_m;
  int plants_seen = 0;
  int crop_seen = 0;
  int weeds_seen = 0;
  int crop_treated = 0;
  int weeds_treated = 0;
  // Not sprayed because the run ended before the bar reached them.
  int crop_not_reached = 0;
  int weeds_not_reached = 0;
  int shots = 0;
  // Weeds seen and not sprayed, less those the bar had not reached when
  // the run ended: what a grower still has to deal with.
  int weeds_left = 0;
  std::optional<double> area_treated_m2;  // from TREATED map cells; none without tiles

  std::vector<std::string> faults;        // vehicle faults, error events, bad messages
  int64_t messages = 0;
  int vehicle_restarts = 0;
};

class RunModel {
 public:
  // Throws InvalidOptionsError.
  explicit RunModel(const RunModelOptions& options = {});

  // Subscriber observer: one message on `channel` (applied or not).
  void Observe(const std::string& channel, bool applied, const telemetry::TelemetrySnapshot& state);
  // Attaches Observe to `subscriber` (the model must outlive it).
  void Follow(telemetry::Subscriber& subscriber);
  // Feeds one logged message to `subscriber` (followed by this model),
  // telling the model which map tile it carries so that a map tile costs
  // one look-up, not a pass over every tile of the run (the report's cost
  // stays linear in distance). Never throws on bad bytes.
  void Feed(telemetry::Subscriber& subscriber, const std::string& channel, const void* data, size_t size,
            int64_t recv_utime);

  // A plant read from elsewhere (an exported map's plants layer) into the
  // registry, as if observed; counts as a message.
  void InsertPlant(const PlantRecord& record);

  const std::optional<telemetry::GridEstimate>& grid() const { return grid_; }
  const std::optional<telemetry::GridEstimate>& truth() const { return truth_; }
  // The vehicle pose to draw: dead reckoning, else simulator truth.
  std::optional<telemetry::Pose> pose() const;
  const std::optional<telemetry::NozzleBar>& nozzles() const { return nozzles_; }
  const std::optional<telemetry::Health>& health() const { return health_; }
  const std::optional<plantscale_thumbnail_t>& thumbnail() const { return thumbnail_; }
  const std::vector<telemetry::PlantObservation>& plants_in_frame() const { return plants_; }
  const std::map<int64_t, PlantRecord>& plants() const { return registry_; }
  const std::map<std::pair<int, int>, telemetry::MapTileDelta>& tiles() const { return tiles_; }
  int tile_revision_sum() const { return tile_revisions_; }
  // The far end along the bed (field y) of the map's tiles: where the
  // newest map row ends; none without tiles.
  std::optional<double> map_front_y_m() const { return map_front_y_m_; }
  int64_t plant_messages() const { return plant_messages_; }  // changes when plants() may have
  const std::vector<TraceSample>& trace() const { return trace_; }
  const std::vector<TraceSample>& truth_trace() const { return truth_trace_; }
  // Per grid message applied, its reception (the receiver's wall clock)
  // minus its stamp (the vehicle's message clock), ms: how far a live
  // station is behind the vehicle's camera (0 for a log, whose clock is
  // the stamps'). Both clocks are one host's in the link tests.
  const std::vector<float>& grid_lag_ms() const { return grid_lag_ms_; }
  // The subscriber's counts per channel, as of the last message.
  const std::map<std::string, telemetry::ChannelStats>& channels() const { return channels_; }
  const std::vector<std::pair<double, double>>& path() const { return path_; }  // field x, y
  const std::vector<telemetry::NozzleShot>& shots() const { return shots_; }
  const std::vector<plantscale_event_t>& events() const { return events_; }
  const std::vector<EventSnapshot>& event_snapshots() const { return event_snapshots_; }
  double distance_m() const { return distance_m_; }
  double speed_m_s() const { return speed_m_s_; }  // mean of the wheel speeds
  int64_t last_message_utime() const { return last_message_utime_; }
  int64_t first_message_utime() const { return first_message_utime_; }
  int64_t messages() const { return messages_; }
  int64_t plantscale_messages() const { return messages_ - unknown_messages_; }  // on our channels

  // Heartbeat state at `now_utime` (the log clock when replaying).
  LinkStatus Link(int64_t now_utime) const;
  // What is wrong, newest last, one line each (subscriber problems included).
  std::vector<std::string> Problems(int64_t now_utime) const;
  RunSummary Summary() const;

 private:
  void ObserveGrid(const telemetry::GridEstimate& grid, std::vector<TraceSample>& trace);
  // The distance driven at `utime` from the odometry heard (interpolated),
  // the newest when `utime` is at or past it or unknown (0).
  double DistanceAt(int64_t utime) const;
  void ObservePlants(const telemetry::TelemetrySnapshot& state);
  void ObserveTiles(const telemetry::TelemetrySnapshot& state);
  void NoteMapFront(const telemetry::MapTileDelta& tile);
  void ObserveHealth(const telemetry::TelemetrySnapshot& state);
  void ObserveEvent(const telemetry::TelemetrySnapshot& state);
  void ObservePose(const telemetry::TelemetrySnapshot& state);

  RunModelOptions options_;
  std::optional<telemetry::GridEstimate> grid_, truth_;
  std::optional<telemetry::Pose> pose_, truth_pose_;
  std::optional<telemetry::NozzleBar> nozzles_;
  std::optional<telemetry::Health> health_;
  int64_t health_recv_utime_ = 0;
  std::optional<plantscale_thumbnail_t> thumbnail_;
  std::vector<telemetry::PlantObservation> plants_;
  std::map<int64_t, PlantRecord> registry_;
  std::map<std::pair<int, int>, telemetry::MapTileDelta> tiles_;
  int tile_revisions_ = 0;
  std::optional<double> map_front_y_m_;
  std::optional<std::pair<int, int>> tile_hint_;  // the tile of the message being fed
  std::vector<TraceSample> trace_, truth_trace_;
  std::vector<float> grid_lag_ms_;
  std::vector<std::pair<double, double>> path_;
  std::vector<telemetry::NozzleShot> shots_;
  std::vector<plantscale_event_t> events_;
  std::optional<plantscale_event_t> finished_;  // run_finished, until the next run_started
  std::vector<EventSnapshot> event_snapshots_;
  std::vector<std::string> vehicle_faults_;
  std::vector<std::string> restarts_;
  std::deque<std::string> subscriber_problems_;
  std::map<std::string, telemetry::ChannelStats> channels_;
  int64_t unknown_messages_ = 0;
  double distance_m_ = 0.0;
  // The last odometry (utime, distance): a grid estimate arrives after its
  // frame was processed (and over a live link after the network's delay),
  // the truth at the capture; each is drawn at the distance of its own
  // time, or the two traces slide apart by the speed times the delay.
  static constexpr size_t kOdometryHistory = 4096;  // 80 s at 50 Hz
  std::deque<std::pair<int64_t, double>> odometry_history_;
  double speed_m_s_ = 0.0;
  int64_t first_boot_utime_ = 0;
  int64_t last_message_utime_ = 0;
  int64_t first_message_utime_ = 0;
  int64_t messages_ = 0;
  int64_t plant_messages_ = 0;
  bool inserted_plants_ = false;  // InsertPlant: a map's plants, no vehicle link
};

// Chi-square quantile with two degrees of freedom: the squared Mahalanobis
// radius that holds `confidence` of a 2-D Gaussian, k² = −2 ln(1 − p).
double EllipseScale2d(double confidence);

}  // namespace plantscale::review
